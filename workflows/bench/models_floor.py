"""The C floor of the models benchmark: cost per right-hand side and per variational derivative
in C (-O3), in Numba loops and inside `flow`, over states along the reference orbit; and the C
values checked against the kernels' at orbit and random states (see `workflows.bench.models`)."""
from functools import lru_cache

import numpy as np
from numba import njit

from rotorsweep.kernels import integrators as ig, models, shooting, stages
from workflows.bench import jeffcott as jc
from workflows.bench.cfloor import flow_ns
from workflows.bench.common import best_time
from workflows.bench.models_points import dop853
from workflows.bench.peers.rotor_c import RotorCFloor

N_CHECK = 200       # orbit states and as many random states at which C and Numba are compared


def _check_states(states, taus, period, rng):
    """N_CHECK states along the orbit and N_CHECK random ones (normal, 1.5x the orbit's spread per
    component: for rigid_preloaded many of them have unloaded balls), with their times."""
    pick = np.linspace(0, len(states) - 1, N_CHECK).astype(int)
    random = rng.normal(size=(N_CHECK, states.shape[1])) * 1.5 * np.abs(states).max(axis=0)
    return np.vstack([states[pick], random]), np.concatenate([taus[pick], rng.uniform(0, period, N_CHECK)])


def _kernel_values(spec, p, taus, states, phi):
    """(f, [f, J phi]) per state from the kernels (models.dispatch.rhs, integrators.derivative)."""
    n = spec.n_state
    f = np.empty_like(states)
    var = np.empty((len(states), n + n * n))
    jbuf = np.empty((n, n))
    for i, (tau, u) in enumerate(zip(taus, states)):
        models.dispatch.rhs(spec.kernel.tag, tau, u, p, f[i])
        ig.derivative(spec.kernel, tau, np.concatenate([u, phi.ravel()]), p, True, var[i], jbuf)
    return f, var


def _rel_diff(a, b):
    """Largest difference relative to the state's largest component (per state), over states."""
    return float((np.abs(a - b).max(axis=1) / np.abs(b).max(axis=1)).max())


def check_c(cf, spec, p, states, taus, period, rng):
    """C against the kernels at N_CHECK orbit + N_CHECK random states, random tangent matrix:
    largest relative difference of f, and of J phi (the variational part)."""
    n = spec.n_state
    phi = rng.normal(size=(n, n))
    st, ta = _check_states(states, taus, period, rng)
    c_f, c_var = cf.values(spec.name, p, ta, st, phi)
    k_f, k_var = _kernel_values(spec, p, ta, st, phi)
    return dict(rhs=_rel_diff(c_f, k_f), var_f=_rel_diff(c_var[:, :n], k_var[:, :n]),
                var_tangent=_rel_diff(c_var[:, n:], k_var[:, n:]), n_states=len(st)), phi


@njit(cache=True, nogil=True, _nrt=False)
def _rhs_steps(tag, taus, states, p, z, du):
    """dispatch.rhs over the states the way the integrators' step loops call it: each state copied
    into a work array (no array view per call) in a loop compiled without reference counting."""
    n = states.shape[1]
    acc = 0.0
    for i in range(taus.size):
        for k in range(n):
            z[k] = states[i, k]
        models.dispatch.rhs(tag, taus[i], z, p, du)
        acc += du[n // 2] + du[n - 1]
    return acc


def rhs_steps(spec, taus, states, p):
    return _rhs_steps(spec.kernel.tag, taus, states, p, np.empty(spec.n_state), np.empty(spec.n_state))


@lru_cache(maxsize=None)
def _constant_size_loop(n):
    """The variational derivative loop of `jeffcott.variational_loop` (rhs_jac + J Phi) with the
    tangent product at the constant size n (a closure constant: LLVM unrolls it), which the
    models' dispatch generates only up to 4 states (`models.generate.FAST_PATH_MAX_STATE`): what
    the derivative would cost with a constant-size copy for this model. Compiled per run (a
    closure is not cached)."""
    @njit(nogil=True, _nrt=False)
    def loop(tag, taus, states, p, z, dz, jbuf):
        acc = 0.0
        for i in range(taus.size):
            for k in range(n):
                z[k] = states[i, k]
            models.dispatch.rhs_jac(tag, taus[i], z, p, dz, jbuf)
            stages.tangent_product(True, z, n, jbuf, dz)
            for k in range(2, n + n * n):
                acc += dz[k]
        return acc
    return loop


def constant_size_var(spec, taus, states, p):
    n = spec.n_state
    z = np.zeros(n + n * n)
    z[n::n + 1] = 1.0
    return _constant_size_loop(n)(spec.kernel.tag, taus, states, p, z, np.empty(n + n * n), np.empty((n, n)))


def _keep_min(row, values):
    for key, v in values.items():
        row[key] = min(row.get(key, np.inf), v)


def _python_costs(peer, taus, states, n=500):
    """ns per call of the scipy peer's numpy right-hand side and augmented system."""
    z = np.concatenate([states[0], np.eye(states.shape[1]).ravel()])
    t_rhs, _ = best_time(lambda: [peer.rhs(taus[i], states[i]) for i in range(n)], 3, 0)
    t_aug, _ = best_time(lambda: [peer.augmented(taus[i], z) for i in range(n)], 3, 0)
    return dict(python_rhs_ns=t_rhs / n * 1e9, python_aug_ns=t_aug / n * 1e9)


def floor_costs(point, ref, n_states, passes):
    """ns per evaluation: C, Numba loops (rhs: the dispatch's rhs; var: integrators._derivative
    with the variational equations) and `flow` / n_rhs over one orbit period, each the best of
    `passes` (the same number for C and Numba: on a loaded machine the chance of an undisturbed
    pass grows with the number of passes), in two interleaved rounds; plus the C-vs-kernel check
    and the peer's numpy costs."""
    spec, p, period = ref["spec"], ref["p"], ref["period"]
    states = shooting.sample_orbit(spec.kernel, ref["state"], p, period, n_states, dop853(1e-12))
    taus = np.arange(n_states) / n_states * period
    row = dict(n_states=n_states, n_var=spec.n_state * (spec.n_state + 1))
    with RotorCFloor() as cf:
        row.update(compiler=cf.compiler, skipped=cf.skipped)
        if cf.compiler:
            row["check"], phi = check_c(cf, spec, p, states, taus, period, np.random.default_rng(7))
        for _ in range(2):      # interleave C and Numba: both see the same machine load
            if cf.compiler:
                c_rhs, _, c_var, _ = cf.measure(spec.name, p, taus, states, phi, passes)
                _keep_min(row, dict(c_rhs_ns=c_rhs, c_var_ns=c_var))
            t_rhs, _ = best_time(lambda: jc.rhs_loop(taus, states, p, model=spec), passes)
            t_var, _ = best_time(lambda: jc.variational_loop(taus, states, p, model=spec), passes)
            t_steps, _ = best_time(lambda: rhs_steps(spec, taus, states, p), passes)
            t_const, _ = best_time(lambda: constant_size_var(spec, taus, states, p), passes)
            _keep_min(row, dict(numba_rhs_ns=t_rhs / n_states * 1e9, numba_rhs_steps_ns=t_steps / n_states * 1e9,
                                numba_var_ns=t_var / n_states * 1e9, numba_var_const_ns=t_const / n_states * 1e9))
            _keep_min(row, flow_ns(p, ref["state"], passes, model=spec, periods=period))
    if not row["compiler"]:
        row.update(c_rhs_ns=np.nan, c_var_ns=np.nan)
    row.update(_python_costs(ref["peer"], taus, states))
    return row
