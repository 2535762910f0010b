"""Smoke tests of the benchmark workflows on tiny grids (the real runs: `make bench`,
`make bench-scaling`), and the shipped write-ups against their JSON."""
import importlib
import json
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs" / "benchmarks"


def test_bench_kernels_imports():
    for name in ("kernels", "jeffcott", "references", "work_precision", "peer_baseline", "cfloor"):
        importlib.import_module(f"workflows.bench.{name}")


def test_shipped_writeups_are_their_json_rendered():
    """docs/benchmarks/README.md, scaling.md and atlas.md are what the templates make of the JSON beside
    them (`--render-only`), so a template edit shows up as a diff of the docs."""
    from workflows.bench.kernels_md import render_readme
    from workflows.bench.scaling_md import markdown

    data = json.loads((DOCS / "results.json").read_text())
    refs = json.loads((DOCS / "reference_points.json").read_text())
    assert render_readme(data, refs) == (DOCS / "README.md").read_text()
    scaling = json.loads((DOCS / "scaling.json").read_text())
    assert markdown(scaling, DOCS / "scaling.png") == (DOCS / "scaling.md").read_text()
    from workflows.bench import atlas
    assert atlas.markdown(json.loads((DOCS / "atlas.json").read_text())) == (DOCS / "atlas.md").read_text()
    from workflows.bench import chunk_plans
    assert chunk_plans.markdown(json.loads((DOCS / "chunk_plans.json").read_text())) == \
        (DOCS / "chunk_plans.md").read_text()


def test_chunk_plan_simulation_on_known_schedules():
    """The list schedule: 4 equal chunks on 2 workers end at 2 chunks + 2 task overheads; a
    first chunk as long as the other three together leaves those three to the other worker.
    Equal segment costs on one line: every plan is within its task overheads and a last chunk
    (<= 4 segments at the 64-point floor and its 32-point steps) of the ideal."""
    import numpy as np

    from rotorsweep.pipeline import sweep
    from workflows.bench import chunk_plans as cp

    o = cp.TASK_OVERHEAD_S
    assert cp.makespan([1.0] * 4, 2) == pytest.approx(2 + 2 * o)
    assert cp.makespan([3.0, 1.0, 1.0, 1.0], 2) == pytest.approx(3 + 3 * o)     # 3 | 1 + 1 + 1
    segs = [sweep.Segment(i, np.zeros((32, 1), int), {}, "speed", np.zeros(32)) for i in range(96)]
    plans = cp.simulate([[(seg, 1.0) for seg in segs]], np.random.default_rng(0))
    for p, by_share in plans.items():
        for v in by_share.values():
            bound = 1.0 + (v["chunks"] * o / p + 4.0) / (96.0 / p)
            assert 1.0 <= v["mean"] <= v["worst"] <= bound


def test_speedup_net_of_steal():
    """Steal on the critical path: all of it with one busy vCPU, half of it with two."""
    from workflows.bench.scaling_ceiling import net_of_steal

    assert net_of_steal(10.0, 6.0, 0.0, 2.0) == 2.0           # 10 / (6 - 1)
    assert net_of_steal(10.5, 5.0, 0.5, 0.0) == 2.0           # (10.5 - 0.5) / 5
    assert net_of_steal(10.0, 6.0, None, 2.0) is None          # not reported: no guess


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_scaling_bench_core_on_a_tiny_grid(tmp_path):
    """1 and 2 workers with default chunks plus one chunk size on 2 workers, 8 points: the JSON
    holds every section and a complete record per run, the Markdown and the plot exist. Slow (45 s:
    three local clusters; the default suite's largest test, and over its timeout under load)."""
    from workflows.bench import scaling as bs
    from workflows.bench.scaling_scene import scene_config

    cfg = scene_config(speed=(100.0, 114.0, 2.0), clearances=(7.6e-6,), name="bench_smoke",
                          segment_length=4)
    assert cfg.n_points == 8 and cfg.data["scene"]["name"] == "bench_smoke"
    out = tmp_path / "out"
    res = bs.run_benchmark(cfg, out, worker_counts=(1, 2), chunk_sizes=[4], mode="quick",
                           work_dir=tmp_path / "work", scheduler_tasks=50)
    data = json.loads((out / "scaling.json").read_text())
    assert data == json.loads(json.dumps(res))
    assert set(bs.RESULT_KEYS) <= set(data)
    assert data["mode"] == "quick" and data["scene"]["n_points"] == 8
    assert [(r["workers"], r["chunk_points"]) for r in data["runs"]] == [(1, None), (2, None), (2, 4)]
    for run in data["runs"]:
        assert set(bs.RUN_KEYS) <= set(run)
        assert run["wall_s"] > 0 and run["points_per_s"] == pytest.approx(8 / run["wall_s"], rel=1e-2)
        assert len(run["worker_max_rss_kib"]) == run["workers"]
        assert all(kib > 10_000 for kib in run["worker_max_rss_kib"])     # > 10 MB: real numbers
        assert run["driver_max_rss_kib"] > 10_000
        assert run["cluster_start_s"] > 0 and run["worker_warmup_s"] > 0
        assert {"compute", "boundaries", "write"} <= set(run["phases"])
        assert run["tasks"]["n_tasks"] == run["n_chunks"] >= 1
        assert run["n_not_converged"] == 0
    assert data["runs"][2]["n_chunks"] == 2                                # 2 segments of 4
    sc = data["scaling"]
    assert sc["speedup"] == pytest.approx(sc["wall_1_worker_s"] / sc["wall_2_workers_s"], rel=1e-2)
    assert sc["target"] == 1.85 and isinstance(sc["meets_target"], bool)
    assert [d["chunk_points_used"] for d in data["chunk_sensitivity"]] == [4, 8]
    assert data["limits"]["cpu_speedup"] > 0 and data["task_costs"]["args_bytes"] > 0
    ceiling = data["ceiling"]                                   # the same chunks without Dask
    assert len(ceiling["walls_1_s"]) == len(ceiling["walls_2_s"]) == 3 and ceiling["cpu_1_s"] > 0
    w1, w2 = ceiling["wall_1_s"], ceiling["wall_2_s"]            # rounded to 1e-4 s, the ratio to 1e-3:
    # the roundings add (the ratio's 5e-4, and the walls' 5e-5 each at their worst)
    assert abs(ceiling["speedup"] - w1 / w2) <= 5e-4 + (w1 + 5e-5) / (w2 - 5e-5) - w1 / w2
    assert {"steal_1_s", "steal_2_s", "speedup_net_of_steal"} <= set(ceiling)
    assert set(data["scheduler"]["by_workers"]) == {"1", "2"}
    assert all(v["batch_tasks_per_s"] > 0 for v in data["scheduler"]["by_workers"].values())
    assert len(data["load_average"]["start"]) == 3 and data["machine"]["cores"] >= 1
    text = (out / "scaling.md").read_text()
    assert "QUICK" in text and "| w2_chunk4 |" in text and "## Verdict" in text
    assert "## Tasks, serialization, CPU time and the scheduler" in text
    assert "## Without Dask: what two busy cores give on this machine" in text
    assert (out / "scaling.png").stat().st_size > 1000
    assert not (tmp_path / "work" / "bench_smoke").exists()               # cubes removed


def test_reductions_bench_on_one_repeat(tmp_path):
    """workflows/bench/reductions.py once: the balanced (one-frequency) orbit is the two-frequency
    one to the Newton tolerance (1e-9 on a state of ~1e-6 m: relative errors below 1e-7) and
    cheaper: the fuller one shoots over 5 support periods, the reduced one over 1 (the work ratio
    is checked, not the measured speed-up, which moves with the machine's load); the cage row and,
    without a `law` key, the cubic-law row say why they are skipped; the shipped write-up is its
    JSON rendered."""
    from workflows.bench import reductions as br

    res = br.main(["--repeats", "1", "--out", str(tmp_path)])
    assert json.loads((tmp_path / "reductions.json").read_text()) == json.loads(json.dumps(res))
    balanced, cage, law = res["rows"]
    assert balanced["reduced"]["status"] == balanced["fuller"]["status"] == 0
    assert balanced["state_error"] < 1e-7 and balanced["half_pp_error"] < 1e-7
    assert balanced["fuller"]["period_s"] == pytest.approx(5 * balanced["reduced"]["period_s"], rel=1e-12)
    assert balanced["speedup"] > 0
    assert "no cage rotation" in cage["skipped"]
    if "law" not in [p.name for p in br.SPEC.parameters]:
        assert "no [bearing] law key" in law["skipped"]
    else:
        assert law["reduced"]["status"] == law["fuller"]["status"] == 0
    shipped = json.loads((DOCS / "reductions.json").read_text())
    assert br.markdown(shipped) == (DOCS / "reductions.md").read_text()


def test_bench_compile_writes_json_and_markdown(tmp_path, monkeypatch):
    """The compile benchmark's plumbing with the measurement stubbed (a real cold run compiles
    for minutes): arguments, provenance, JSON and the write-up from it."""
    from workflows.bench import compile as bc

    times = {"cold": {"wall_s": 9.0, "cpu_s": 8.0, "load_before": [1.0, 1.0, 1.0]},
             "warm": {"wall_s": 0.9, "cpu_s": 0.8, "load_before": [1.0, 1.0, 1.0]}}
    monkeypatch.setattr(bc, "measure", lambda trees, models: {lab: {m: times for m in models} for lab in trees})
    result = bc.main(["--models", "duffing", "--out", str(tmp_path)])
    head = bc.label(bc.WORKTREE)        # the working tree's commit, + when it has changes
    assert result["results"] == {head: {"duffing": times}}
    assert len(result["runs"]) == 1 and {"date", "machine", "load", "command"} <= set(result["runs"][0])
    assert json.loads((tmp_path / "compile.json").read_text()) == result
    assert f"| `{head}` | duffing | 9.0 | 8.0 | 1.0 | 0.9 | 0.8 |" in (tmp_path / "compile.md").read_text()
    # several warm runs: the median and their range
    times["warm"].update(runs_wall_s=[1.1, 0.9, 0.85], runs_cpu_s=[1.0, 0.8, 0.8])
    bc.main(["--models", "duffing", "--out", str(tmp_path)])
    assert f"| `{head}` | duffing | 9.0 | 8.0 | 1.0 | 0.9 (0.85-1.1) | 0.8 |" in (tmp_path / "compile.md").read_text()


def test_shipped_compile_writeup_is_its_json_rendered():
    from workflows.bench.compile import markdown

    assert markdown(json.loads((DOCS / "compile.json").read_text())) == (DOCS / "compile.md").read_text()


def test_backbone_bench_on_a_small_grid(tmp_path):
    """workflows/bench/backbone.py on symmetric4 with 9 amplitudes: every mode's manifold parts from
    the continuation at the cubic theory's order 4 (+-0.3: the lowest decade holds 5 points of a
    difference whose next order is (A / z0)^2 <= 1e-2 smaller), the JSON is what it returns, and the
    shipped write-up is its JSON rendered."""
    from workflows.bench import backbone as bb

    res = bb.main(["--scenes", "configs/filipkovsky2010_symmetric.toml", "--grid-points", "9", "--repeats", "1",
                   "--out", str(tmp_path)])
    assert json.loads((tmp_path / "backbone.json").read_text()) == json.loads(json.dumps(res))
    assert [r["mode"] for r in res["rows"]] == [1, 2, 3, 4]
    assert all(abs(r["slope"] - 4.0) < 0.3 and r["continuation_end"] == "left_range" for r in res["rows"])
    shipped = json.loads((DOCS / "backbone.json").read_text())
    assert bb.markdown(shipped) == (DOCS / "backbone.md").read_text()


def test_models_c_floor_equals_the_kernels():
    """rotor_rhs.c (the C floor of `make bench-models`) computes the kernels' right-hand side and
    variational derivative at each benchmark point's parameters, at random states (rigid_preloaded:
    many balls unloaded) and a random tangent matrix. Both do the same floating-point operations up
    to the order of short sums (~10 terms, a few ulps of the largest); 1e-12 relative to the state's
    largest component leaves 1000x for cancellation between bearing force and forcing."""
    import numpy as np

    from rotorsweep.kernels import models
    from workflows.bench.models import POINTS
    from workflows.bench.models_floor import check_c
    from workflows.bench.models_points import point_values
    from workflows.bench.peers.rotor_c import RotorCFloor

    with RotorCFloor() as cf:
        if cf.compiler is None:
            pytest.skip(cf.skipped)
        for point in POINTS[1:]:        # one point per model
            spec = models.get(point["model"])
            p = spec.build(point_values(spec, point)).p
            rng = np.random.default_rng(3)
            states = rng.normal(scale=5.0, size=(50, spec.n_state))
            diff, _ = check_c(cf, spec, p, states, rng.uniform(0, 1, 50), 1.0, rng)
            assert max(diff["rhs"], diff["var_f"], diff["var_tangent"]) < 1e-12, (point["name"], diff)


def test_models_scipy_peers_compute_the_kernels_equations():
    """The scipy peers of `make bench-models` (numpy ball sums from the balls' contact directions;
    the polynomial form's tensors) give the kernels' right-hand side and variational derivative at
    random states: "equal tolerance on the same equations" needs the same equations. Different
    summation orders and, for the series rotors, the tensors' M^-1 contractions cost a few ulps of
    the largest term; 1e-11 relative to each vector's largest component bounds that with room for
    cancellation."""
    import numpy as np

    from rotorsweep.kernels import integrators as ig, models
    from workflows.bench.models import POINTS
    from workflows.bench.models_points import prepare_peer

    for point in POINTS[1:]:
        spec = models.get(point["model"])
        peer, p = prepare_peer(spec, point)
        n = spec.n_state
        rng = np.random.default_rng(5)
        for u in rng.normal(scale=5.0, size=(10, n)):
            tau = rng.uniform()
            du, z = np.empty(n), np.concatenate([u, rng.normal(size=n * n)])
            models.dispatch.rhs(spec.kernel.tag, tau, u, p, du)
            np.testing.assert_allclose(peer.rhs(tau, u), du, rtol=0, atol=1e-11 * np.abs(du).max())
            dz = np.empty(n + n * n)
            ig.derivative(spec.kernel, tau, z, p, True, dz, np.empty((n, n)))
            got = peer.augmented(tau, z)
            np.testing.assert_allclose(got[:n], du, rtol=0, atol=1e-11 * np.abs(du).max())
            np.testing.assert_allclose(got[n:], dz[n:], rtol=0, atol=1e-11 * np.abs(dz[n:]).max())


def test_shipped_models_writeup_is_its_json_rendered():
    """docs/benchmarks/models.md is models.json rendered, with a row per point and rtol, and the C
    check recorded in the run below 1e-12."""
    from workflows.bench.models import POINTS
    from workflows.bench.models_md import markdown

    data = json.loads((DOCS / "models.json").read_text())
    assert markdown(data) == (DOCS / "models.md").read_text()
    assert [pt["name"] for pt in data["points"]] == [p["name"] for p in POINTS]
    for pt, point in zip(data["points"], POINTS):
        assert [r["rtol"] for r in pt["rows"]] == list(point["rtols"])
        assert all(r["ours"]["converged"] and r["scipy"]["converged"] for r in pt["rows"])
        assert max(pt["floor"]["check"][k] for k in ("rhs", "var_f", "var_tangent")) < 1e-12
    assert {"date", "machine", "load", "command"} <= set(data)


def _attractor_cube(att, k, lle, se, method):
    """A (speed, clearance) cube of attractor variables on 5 speeds x 1 clearance."""
    import numpy as np
    import xarray as xr

    dims = ("speed", "clearance")
    col = lambda v, dtype=float: (dims, np.asarray(v, dtype)[:, None])
    return xr.Dataset({"attractor": col(att, int), "period": col(k, int), "lle": col(lle), "lle_stderr": col(se),
                       "lle_method": col(method, int), "forcing_period": ("speed", np.full(5, 0.01))},
                      coords={"speed": [10.0, 10.1, 10.2, 10.3, 10.4], "clearance": [19e-6]})


def test_attractor_accuracy_counts_what_differs():
    """workflows.attractor_accuracy on a hand-made pair: one class change next to a change of the
    reference attractor (near), one far from any (3 grid speeds from the only change), one
    period change; exponents by the three rules (derived: ln|lambda| = lle k T to 1e-5, derived
    vs integrated 3 se or 1e-3, both integrated 3 combined se)."""
    from rotorsweep.kernels import attractor as at
    from workflows import attractor_accuracy as acc

    P, C, Q = at.PERIODIC, at.CHAOTIC, at.QUASI_PERIODIC
    ref = _attractor_cube([P, P, P, P, C], [1, 1, 1, 1, 0], [-5.0, -5.0, -5.0, -5.0, 40.0],
                          [0, 0, 0, 0, 2.0], [1, 1, 1, 1, 0])
    fast = _attractor_cube([Q, P, P, P, C], [0, 1, 2, 1, 0], [0.1, -5.0, -5.0 + 1.1e-3, -5.0, 46.5],
                           [0.1, 0, 0, 0, 2.0], [0, 1, 1, 1, 0])
    cmp = acc.compare(fast, ref)
    assert cmp["classes"]["periodic"] == {"points": 4, "disagree": 1, "near": 0}
    assert cmp["classes"]["chaotic"] == {"points": 1, "disagree": 0, "near": 0}
    assert [(d["speed"], d["reference"], d["fast"], d["near"]) for d in cmp["differences"]] == [
        (10.0, "period 1", "quasi periodic", False), (10.2, "period 1", "period 2", True)]
    assert (cmp["periodic_both"], cmp["period_agree"]) == (3, 2)
    # 46.5 vs 40 +- 2 and 2: 6.5 <= 3 x 2.83; 10.2 Hz: 1.1e-3 1/s x T 0.01 s = 1.1e-5 > 1e-5
    assert cmp["exponents"] == {"both derived": {"points": 3, "agree": 2},
                                "derived vs integrated": {"points": 1, "agree": 0},
                                "both integrated": {"points": 1, "agree": 1}}
    assert "| 10.0 | 19.0 | period 1 | quasi periodic | no |" in acc.markdown(cmp)


def test_shipped_attractor_cost_writeup_is_its_json_rendered():
    from workflows import attractor_cost

    res = json.loads((DOCS / "attractor_cost.json").read_text())
    assert attractor_cost.report(res) == (DOCS / "attractor_cost.md").read_text()


def test_extrema_writeup_is_its_json_rendered():
    """docs/benchmarks/extrema.md is what workflows.bench.extrema makes of extrema.json."""
    from workflows.bench import extrema
    assert extrema.markdown(json.loads((DOCS / "extrema.json").read_text())) == (DOCS / "extrema.md").read_text()
