"""The C floor: cost per right-hand-side evaluation in plain C, in Numba loops, inside `flow`,
and in the scipy peer's numpy functions, over the same states along each reference orbit."""
import numpy as np

from workflows.bench import jeffcott as jc
from workflows.bench.common import best_time, log
from workflows.bench.peers.jeffcott_c import CFloor
from workflows.bench.peers.jeffcott_scipy import ScipyPeer

# (key, settings, periods integrated, variational) of the `flow` runs timed per evaluation
FLOW_COSTS = (("flow_dop853_ns", jc.dop853(1e-10, 1e-12), 20.0, False),
              ("flow_rk4_ns", jc.rk4(512), 20.0, False),
              ("flow_dop853_var_ns", jc.dop853(1e-10, 1e-12), 1.0, True),
              ("flow_rk4_var_ns", jc.rk4(512), 1.0, True))


def _ns_per_call(fn, n_calls, repeats):
    t, result = best_time(fn, repeats)
    return t / n_calls * 1e9, result


def flow_ns(p, u0, repeats, model=jc.JEFF, periods=None):
    """{FLOW_COSTS key: ns per evaluation}: time of `flow` divided by its n_rhs (over `periods`
    instead of the FLOW_COSTS periods when given)."""
    out = {}
    for key, opts, t1, var in FLOW_COSTS:
        z0 = jc.initial_state(u0, var, model.n_state)
        t, (_, _, n_rhs) = best_time(lambda: jc.flow(p, z0, opts, var, t1=periods or t1, model=model), repeats)
        out[key] = t / n_rhs * 1e9
    return out


def _python_rhs_cost(p, taus, states, n=2000):
    peer = ScipyPeer(jc.named_params(p))
    z = np.concatenate([states[0], np.eye(4).ravel()])
    t_rhs, _ = best_time(lambda: [peer.rhs(taus[i], states[i]) for i in range(n)], 3, 0)
    t_aug, _ = best_time(lambda: [peer.augmented(taus[i], z) for i in range(n)], 3, 0)
    return t_rhs / n * 1e9, t_aug / n * 1e9


def _keep_min(row, values):
    for key, v in values.items():
        row[key] = min(row.get(key, np.inf), v)


def _point_costs(cf, e, n_states, passes, repeats):
    p, s_ref = np.array(e["p"]), np.array(e["state"])
    # states along the reference orbit (the contact pattern an integrator sees), with their times
    states = jc.sample_orbit(p, s_ref, n_states, jc.dop853(1e-12, 1e-14))
    taus = np.arange(n_states) / n_states
    row, sums = dict(point=e["name"]), {}
    for _ in range(2):    # interleave C and Numba so that both see the same machine load
        if cf.compiler:
            c_rhs, sums["c_rhs"], c_var, sums["c_var"] = cf.measure(e["name"], p, taus, states, passes)
            _keep_min(row, dict(c_rhs_ns=c_rhs, c_var_ns=c_var))
        numba = {}
        numba["numba_rhs_ns"], sums["numba_rhs"] = _ns_per_call(lambda: jc.rhs_loop(taus, states, p), n_states, repeats)
        numba["numba_force_ns"], sums["numba_force"] = _ns_per_call(
            lambda: jc.force_loop(taus, states, p), n_states, repeats)
        numba["numba_var_ns"], sums["numba_var"] = _ns_per_call(
            lambda: jc.variational_loop(taus, states, p), n_states, repeats)
        _keep_min(row, numba)
        _keep_min(row, flow_ns(p, s_ref, repeats))
    if cf.compiler:
        row["checksum_rel_diff_rhs"] = abs(sums["c_rhs"] - sums["numba_rhs"]) / abs(sums["numba_rhs"])
        row["checksum_rel_diff_var"] = abs(sums["c_var"] - sums["numba_var"]) / abs(sums["numba_var"])
    else:
        row.update(c_rhs_ns=np.inf, c_var_ns=np.inf)
    row["python_rhs_ns"], row["python_aug_ns"] = _python_rhs_cost(p, taus, states)
    return row, taus, states


def integrator_overhead(taus, states, repeats):
    """The integrators' own cost per evaluation: the same flows on the linear oscillator, whose
    right-hand side is a few multiplications, minus its variational derivative in an njit loop
    (the J Phi product): what remains is the stage sums, the error norm and the step control."""
    p = np.array([40.0, 5.0, 90.0, 0.4, 0.9])
    u0 = np.array([1.0, -2.0, 0.5, 0.3])
    out = {}
    for _ in range(3):      # three interleaved rounds, best of each: the machine is shared
        _keep_min(out, flow_ns(p, u0, repeats, model=jc.LINEAR, periods=1.0))
        t, _ = best_time(lambda: jc.variational_loop(taus, states, p, model=jc.LINEAR), repeats)
        _keep_min(out, dict(derivative_var_ns=t / taus.size * 1e9))
    return out


def c_floor(refs, n_states, passes, repeats):
    """Cost per right-hand-side evaluation: C, Numba in an njit loop, Numba inside `flow`."""
    with CFloor() as cf:
        out = dict(points=[], compiler=cf.compiler, skipped=cf.skipped)
        for e in refs["points"]:
            row, taus, states = _point_costs(cf, e, n_states, passes, repeats)
            out["points"].append(row)
            log(f"  C floor {e['name']}: done")
    out["integrator_only"] = integrator_overhead(taus, states, repeats)
    return out
