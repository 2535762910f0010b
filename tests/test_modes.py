"""`rotorsweep modes` for every model with a linearization, and the one linear-modes function
(rotorsweep.kernels.modal) against closed forms."""
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from rotorsweep.pipeline import cli, modes
from rotorsweep.kernels import modal, models

ROOT_CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def test_damped_two_dof_modes_against_the_closed_form():
    """Uncoupled m_i x'' + c_i x' + k_i x = 0: s = -c / 2m +- i sqrt(k/m - (c/2m)^2); the damped and
    undamped frequencies and zeta = c / (2 sqrt(k m)) to rounding (a 4x4 eigenproblem: 1e-12)."""
    m, c, k = np.array([2.0, 1.0]), np.array([0.4, 3.0]), np.array([50.0, 400.0])
    found = modal.modes_of(np.diag(m), np.diag(c), np.zeros((2, 2)), np.diag(k), None)
    w_n = np.sqrt(k / m)
    zeta = c / (2 * np.sqrt(k * m))
    order = np.argsort(w_n * np.sqrt(1 - zeta ** 2))
    for mode, i in zip(found, order):
        assert mode.omega == pytest.approx(w_n[i] * np.sqrt(1 - zeta[i] ** 2), rel=1e-12)
        assert mode.undamped_frequency == pytest.approx(w_n[i] / (2 * np.pi), rel=1e-12)
        assert mode.damping_ratio == pytest.approx(zeta[i], rel=1e-12)
        assert (mode.whirl, mode.label) == ("none", "unknown")


def test_gyroscopic_pair_whirls_backward_below_and_forward_above():
    """m (x'' , y'') + g (y', -x') + k (x, y) = 0: x = cos, y = sin (forward whirl) solves it when
    m w^2 - g w - k = 0, so forward w = (g + sqrt(g^2 + 4 m k)) / 2m, backward (-g + ...) / 2m."""
    m, g, k = 1.5, 0.8, 30.0
    gyro = np.array([[0.0, g], [-g, 0.0]])
    found = modal.modes_of(m * np.eye(2), np.zeros((2, 2)), gyro, k * np.eye(2), modal.kinds_from_names(("x", "y")))
    root = np.sqrt(g * g + 4 * m * k)
    assert [mode.whirl for mode in found] == ["backward", "forward"]
    np.testing.assert_allclose([mode.omega for mode in found], [(root - g) / (2 * m), (root + g) / (2 * m)], rtol=1e-12)


def test_modes_of_duffing_json_against_the_closed_form(capsys):
    """Duffing's declared linearization x'' + 2 zeta x' + x = 0: w_n = 1, zeta as given, f_d =
    sqrt(1 - zeta^2) / 2 pi; log decrement 2 pi zeta / sqrt(1 - zeta^2)."""
    assert cli.main(["modes", str(ROOT_CONFIGS / "duffing_resonance.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    (mode,) = out["modes"]
    zeta = 0.05
    assert mode["undamped_frequency_hz"] == pytest.approx(1 / (2 * np.pi), rel=1e-12)
    assert mode["damped_frequency_hz"] == pytest.approx(np.sqrt(1 - zeta ** 2) / (2 * np.pi), rel=1e-12)
    assert mode["damping_ratio"] == pytest.approx(zeta, rel=1e-12)
    assert mode["log_decrement"] == pytest.approx(2 * np.pi * zeta / np.sqrt(1 - zeta ** 2), rel=1e-12)


def test_modes_text_labels_damped_and_undamped_frequencies(capsys):
    assert cli.main(["modes", str(ROOT_CONFIGS / "filipkovsky2010_symmetric.toml")]) == 0
    text = capsys.readouterr().out
    assert "damped frequency f_d" in text and "undamped f_n" in text and "at 100 Hz shaft speed" in text
    assert len([line for line in text.splitlines() if line.split()[:1] and line.split()[0].isdigit()]) == 4


def test_modes_of_the_clearance_rotor_says_why_not_in_one_line(capsys):
    spec = models.get("jeffcott_clearance")
    assert not spec.has_linearization
    assert cli.main(["modes", str(ROOT_CONFIGS / "bai2006_fig13.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "model jeffcott_clearance has no linearization: its bearing stiffness varies" in err


AXES_WITHOUT_UNSET = {"duffing": {"omega": 1.0}, "rigid_preloaded": {"speed": 250.0}}   # the build needs them


@pytest.mark.parametrize("name", [n for n, s in models.REGISTRY.items() if s.has_linearization])
def test_declared_linearization_equals_the_kernels_jacobian_at_the_equilibrium(name):
    """The spec's capability and the kernel agree: the eigenvalues of the model's Jacobian
    (dispatch.jac, scaled time) at its static equilibrium, over the period, are the modes'
    s = -zeta w_n + i w_d (SI). Two assemblies of one matrix: rounding only, 1e-9 relative."""
    from rotorsweep.kernels.models import dispatch

    spec = models.get(name)
    values = {p.name: (p.unset if p.axis else p.default) for p in spec.parameters}
    values.update(AXES_WITHOUT_UNSET.get(name, {}))
    eq, _ = spec.linear_system(values)
    built = spec.build(values)
    u = np.zeros(spec.n_state)
    u[:spec.n_position] = eq.position / spec.length_scale
    jac = np.zeros((spec.n_state, spec.n_state))
    dispatch.jac(spec.kernel[0], 0.0, u, built.p, jac)
    s_kernel, _ = modal.eigenpairs(jac)
    s_kernel = s_kernel / built.period
    found = modes.modes(spec, values)
    s_spec = np.array([complex(-m.damping_ratio * m.undamped_frequency, m.frequency) for m in found]) * 2 * np.pi
    np.testing.assert_allclose(s_kernel, s_spec, rtol=1e-9, atol=1e-9 * np.abs(s_spec).max())


SYMMETRIC = str(ROOT_CONFIGS / "filipkovsky2010_symmetric.toml")


@pytest.mark.parametrize("args, message", [
    (["--at", "speed=-5"], "--at speed=-5: must be >= 0 and <= 100000 (got -5) (the limits of speed"),
    (["--at", "speed=nan"], "--at speed=nan: must be a finite number"),
    (["--at", "nosuch=1"], "--at nosuch: not an axis of model symmetric4 (axes: speed, nominal_angle, contact_angle"),
    (["--at", "speed"], "--at speed: expected AXIS=VALUE"),
    (["--campbell", "0:1000:100000000", "-o", "c.csv"], "--campbell 0:1000:100000000: NUM must be 1 to 200000"),
    (["--campbell", "0:1000", "-o", "c.csv"], "--campbell 0:1000: expected START:STOP:NUM"),
    (["--campbell", "0:1000:ten", "-o", "c.csv"], "--campbell 0:1000:ten: expected START:STOP:NUM"),
    (["--campbell", "0:inf:10", "-o", "c.csv"], "--campbell 0:inf:10: STOP must be a finite number"),
    (["--campbell=-10:100:10", "-o", "c.csv"], "--campbell -10:100:10: START must be >= 0")])
def test_bad_at_and_campbell_values_are_one_line_naming_the_option(args, message, tmp_path, monkeypatch, capsys):
    """Issue 36 items 4 and 8: checked like config axes (names, limits, finite, size) before any work."""
    monkeypatch.chdir(tmp_path)
    assert cli.main(["modes", SYMMETRIC, *args]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "c.csv").exists()


def test_a_failing_linearization_names_the_option_not_the_solver(monkeypatch, capsys):
    def singular(*_):
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(modal, "modes_of", singular)
    assert cli.main(["modes", SYMMETRIC, "--at", "speed=50"]) == 2
    err = capsys.readouterr().err
    assert "--at: no linearization at speed=50" in err and len(err.strip().splitlines()) == 1


def test_the_campbell_csv_is_written_atomically_and_a_full_disk_names_the_path(tmp_path, monkeypatch, capsys):
    out = tmp_path / "campbell.csv"
    out.write_text("the previous table\n")
    real = modes.csv.writer

    class FullDisk:
        def __init__(self, fh):
            self.w = real(fh)

        def writerow(self, row):
            self.w.writerow(row)

        def writerows(self, rows):
            raise OSError(28, "No space left on device")

    monkeypatch.setattr(modes.csv, "writer", FullDisk)
    assert cli.main(["modes", SYMMETRIC, "--campbell", "0:100:5", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"modes -o {out}: No space left on device" in err and len(err.strip().splitlines()) == 1
    assert out.read_text() == "the previous table\n" and list(tmp_path.iterdir()) == [out]
    monkeypatch.undo()
    assert cli.main(["modes", SYMMETRIC, "--campbell", "0:100:5", "-o", str(out)]) == 0
    assert len(out.read_text().splitlines()) == 1 + 5 * 4


def test_campbell_without_an_output_file_is_refused(capsys):
    """--campbell without -o computed nothing and said nothing."""
    assert cli.main(["modes", SYMMETRIC, "--campbell", "0:100:3"]) == 2
    assert "give -o FILE.csv" in capsys.readouterr().err


def _tilting_rotor(i_d, i_p, k):
    """modes_at(speed [Hz]) of the tilting rotor I_d (a'' , b'') + I_p W (b', -a') + k (a, b) = 0
    (W = 2 pi speed): forward w = (I_p W + sqrt((I_p W)^2 + 4 I_d k)) / 2 I_d, backward with -I_p W."""
    kinds = modal.kinds_from_names(("x", "y"))

    def modes_at(speed):
        w = 2 * np.pi * speed
        gyro = i_p * w * np.array([[0.0, 1.0], [-1.0, 0.0]])
        return modal.modes_of(i_d * np.eye(2), np.zeros((2, 2)), gyro, k * np.eye(2), kinds)
    return modes_at


def test_critical_speeds_of_a_gyroscopic_rotor_against_the_closed_form_and_brentq():
    """1x crossings: I_d w^2 -+ I_p w^2 = k, so W = sqrt(k / (I_d +- I_p)) (backward +, forward -);
    a support line f_s crosses the forward mode where I_p W w = I_d w^2 - k (w = 2 pi f_s), the
    backward one where I_p W w = k - I_d w^2. The crossing is located to 1e-12 of the top speed
    (CRITICAL_XTOL) and the frequencies are exact to rounding: rtol 1e-9."""
    i_d, i_p, k = 2.0, 0.8, 4.0e6
    modes_at = _tilting_rotor(i_d, i_p, k)
    speeds = np.linspace(0, 400, 81)[1:]
    # at rest both modes are at sqrt(k / I_d) / 2 pi = 225 Hz: the backward one falls through 160 Hz,
    # the forward one rises through 300 Hz
    lines = [modes.Line("1x", 1.0, 0.0), modes.Line("low", 0.0, 160.0), modes.Line("high", 0.0, 300.0)]
    found = modes.critical_speeds(modes_at, speeds, lines)
    one_x = {c.whirl: c.speed_hz for c in found if c.line == "1x"}
    assert one_x["backward"] == pytest.approx(np.sqrt(k / (i_d + i_p)) / (2 * np.pi), rel=1e-9)
    assert one_x["forward"] == pytest.approx(np.sqrt(k / (i_d - i_p)) / (2 * np.pi), rel=1e-9)
    w = 2 * np.pi * 300.0
    support = {c.whirl: c for c in found if c.line != "1x"}
    assert support["forward"].speed_hz == pytest.approx((i_d * w * w - k) / (i_p * w) / (2 * np.pi), rel=1e-9)
    w = 2 * np.pi * 160.0
    backward = brentq(lambda s: (-i_p * 2 * np.pi * s + np.sqrt((i_p * 2 * np.pi * s) ** 2 + 4 * i_d * k))
                      / (2 * i_d) - w, 1e-3, 400)
    assert support["backward"].speed_hz == pytest.approx(backward, rel=1e-9)
    targets = {"1x": None, "low": 160.0, "high": 300.0}
    assert all(c.frequency_hz == pytest.approx(targets[c.line] or c.speed_hz, rel=1e-9) for c in found)
    assert len(found) == 4


def test_modes_json_lists_critical_speeds_on_the_1x_line(capsys):
    """Every listed 1x critical speed of the 2016 rotor has its damped frequency equal to the speed
    (the root solve's residual, 1e-9 relative), its mode's frequency at that speed recomputed."""
    assert cli.main(["modes", str(ROOT_CONFIGS / "filipkovsky2016_fig2a.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    crit = [c for c in out["critical_speeds"] if c["line"] == "1x"]
    assert len(crit) >= 3 and out["critical_speed_search_hz"][1] > crit[-1]["speed_hz"]
    for c in crit:
        assert c["frequency_hz"] == pytest.approx(c["speed_hz"], rel=1e-9)


def test_modes_text_lists_critical_speeds(capsys):
    assert cli.main(["modes", str(ROOT_CONFIGS / "filipkovsky2010_symmetric.toml")]) == 0
    text = capsys.readouterr().out
    assert "critical speeds (damped frequency = excitation line)" in text and " 1x " in text


def test_station_shapes_of_a_whirling_pair_are_circles_turning_with_the_whirl():
    """Forward whirl x = cos, y = sin is X = 1, Y = -i (y = Re(-i e^{i theta}) = sin theta);
    backward Y = +i X: the station's orbit is a circle run the whirl's way (exact: rtol 1e-12)."""
    modes_at = _tilting_rotor(2.0, 0.8, 4.0e6)
    for mode in modes_at(100.0):
        ((station, (x, y)),) = modes.station_shapes(mode, ("x", "y")).items()
        assert station is None
        assert y / x == pytest.approx(-1j if mode.whirl == "forward" else 1j, rel=1e-12)


def test_mode_shapes_figure_has_a_panel_per_mode():
    from rotorsweep.pipeline import config
    from rotorsweep.pipeline.report import style
    from rotorsweep.pipeline.report.figures import mode_shapes
    scene = config.load_config(ROOT_CONFIGS / "filipkovsky2010_symmetric.toml").scene
    found, coordinates, disk = mode_shapes.scene_modes(scene)
    fig = mode_shapes.fig_mode_shapes(scene, "bokeh")
    assert len(fig) == len(found) == 4 and disk == (0.25, 0.5)
    assert [c.label for c in fig.values()[0].values() if c.label] == ["station 1", "station 2", "disc"]
    with style.backend("bokeh") as hv:
        hv.render(fig, backend="bokeh")


def test_an_undamped_scene_has_exactly_zero_damping_in_every_table_and_the_campbell_colours():
    """The 2010 papers' rotor has no damping: the eigen-solver's noise in -Re s / |s| (1e-17 to
    4e-16 here, as modal.modes_of gives it) lies below modes.zeta_rounding's LAPACK error bound
    (2e-15 to 1.5e-14) and comes out as exactly 0: the table, --json and the Campbell diagram's colour
    scale of the damping ratio."""
    from rotorsweep.pipeline import config
    from rotorsweep.pipeline.report.figures import mode_campbell

    cfg = config.load_config(ROOT_CONFIGS / "filipkovsky2010_symmetric.toml", whole_grid=False)
    spec, values = cfg.model, modes.scene_values(cfg.scene, modes.at_point(cfg, {}))
    _, system = spec.linear_system(values)
    raw = [m.damping_ratio for m in modal.modes_of(system.M, system.C, system.G, system.K, None)]
    upper, rounding = modes.zeta_rounding(system)
    assert any(z != 0.0 for z in raw) and max(np.abs(raw)) <= min(rounding) < 1e-13
    assert [m["damping_ratio"] for m in modes.records(spec, values)["modes"]] == [0.0] * 4
    assert {row[3] for row in modes.campbell(spec, values, [0.0, 100.0, 400.0, 1000.0])} == {0.0}
    diagram = mode_campbell.fig_mode_campbell(cfg.scene, "bokeh", speeds=np.linspace(10.0, 1000.0, 12))[0]
    (points,) = [e for e in diagram if "zeta" in [d.name for d in e.vdims]]
    assert set(points.dimension_values("zeta")) == {0.0}


def test_a_light_but_real_damping_ratio_is_kept():
    """x'' + 2 zeta x' + x = 0 with zeta = 1e-9: far above the rounding bound of this 2x2
    problem (2 eps ||B||_1 / |s| ~ 1e-15), the damping ratio is zeta to the eigenvalue's own
    error, eps |s| = 2e-16 absolute."""
    from rotorsweep.pipeline import config

    text = (ROOT_CONFIGS / "duffing_resonance.toml").read_text().replace("zeta = 0.05", "zeta = 1e-9")
    cfg = config.parse_config(text)
    (mode,) = modes.records(cfg.model, modes.scene_values(cfg.scene, modes.at_point(cfg, {})))["modes"]
    assert mode["damping_ratio"] == pytest.approx(1e-9, abs=1e-15)
