"""The per-point half of the models benchmark: tight references and the timed solves, ours
against the scipy peer at equal tolerances (see `workflows.bench.models`)."""
import numpy as np

from rotorsweep.kernels import continuation, floquet, integrators as ig, models, shooting
from rotorsweep.kernels.continuation.arclength import Settings
from rotorsweep.kernels.continuation.backbone import follow_backbone
from rotorsweep.kernels.models import rigid_preloaded as rp
from rotorsweep.kernels.orbits import AutonomousOrbitProblem
from workflows.bench.peer_baseline import time_pair
from workflows.bench.peers.rotor_scipy import RigidPreloadedPeer, SeriesRotorPeer
from workflows.bench.references import complex_list, match


def dop853(rtol, atol=None):
    return ig.settings("dop853", rtol=rtol, atol=rtol * 1e-2 if atol is None else atol)


def rel_error(s, ref):
    """max-norm of the state difference relative to the reference's largest component."""
    return float(np.abs(np.asarray(s) - ref).max() / np.abs(ref).max())


def point_values(spec, point, **over):
    v = {par.name: (par.unset if par.axis else par.default) for par in spec.parameters}
    return {**v, **point["values"], **over}


def _rigid_params(p):
    """rigid_preloaded's parameter vector by name, for the peer (which does not read offsets)."""
    blocks = dict(gain=rp.P_GAIN, damp=rp.P_DAMP)
    vectors = dict(const=rp.P_CONST, ucos=rp.P_UCOS, usin=rp.P_USIN, sup=rp.P_SUP)
    if p[rp.P_LAW] != rp.LAWS["ball_sum"]:
        raise ValueError("the rigid_preloaded peers write the ball sum: law must be ball_sum")
    return {**{k: p[i:i + 25].reshape(5, 5) for k, i in blocks.items()},
            **{k: p[i:i + 5] for k, i in vectors.items()},
            **{k: p[i] for k, i in dict(wu=rp.P_WU, ws=rp.P_WS, offset=rp.P_OFFSET, cos_a=rp.P_COS_A,
                                         sin_a=rp.P_SIN_A, n_balls=rp.P_NBALLS).items()}}


class _Counting(AutonomousOrbitProblem):
    """AutonomousOrbitProblem that adds up its right-hand sides in `COUNT` (untimed runs only)."""
    __slots__ = ()
    COUNT = [0]

    def residual(self, s, period):
        out = super().residual(s, period)
        self.COUNT[0] += out[4]
        return out


# --- our solves and the peer's, one signature: (state, period, multipliers, iterations, n_rhs, ok)

def ours_forced(ref, rtol, guess, tol):
    # plain Newton, the peer's algorithm (the staged Newton for far starts is compared in kernels.md)
    sol = shooting.periodic_orbit(ref["spec"], guess, ref["p"], dop853(rtol), tol=tol, staged=False)
    return sol.state, 1.0, floquet.multipliers(sol.monodromy), sol.iterations, sol.n_rhs, sol.status == 0


def peer_forced(ref, rtol, guess, tol):
    s, mono, its, nfev, ok = ref["peer"].shoot(guess, "DOP853", rtol, rtol * 1e-2, tol)
    return s, 1.0, np.linalg.eigvals(mono), its, nfev, ok


def ours_autonomous(ref, rtol, guess, tol, problem=AutonomousOrbitProblem):
    _Counting.COUNT[0] = 0
    orb = problem(ref["spec"], ref["p"], dop853(rtol), ref["j"]).solve(ref["amplitude"], guess, ref["period_guess"], tol)
    return orb.state, orb.period, orb.multipliers, orb.iterations, _Counting.COUNT[0], orb.converged


def peer_autonomous(ref, rtol, guess, tol):
    s, period, mono, its, nfev, ok = ref["peer"].solve(ref["amplitude"], ref["j"], guess, ref["period_guess"],
                                                       "DOP853", rtol, rtol * 1e-2, tol)
    return s, period, np.linalg.eigvals(mono), its, nfev, ok


def _errors(ref, out):
    s, period, lam = out[:3]
    return dict(err_state=rel_error(s, ref["state"]), err_period=abs(period / ref["period"] - 1.0),
                err_mult=match(lam, ref["multipliers"]), iterations=int(out[3]), n_rhs=int(out[4]),
                converged=bool(out[5]))


# --- references ---------------------------------------------------------------------------------

def _forced_start(spec, point):
    """The orbit at the point by natural continuation along point['approach'] (as a sweep)."""
    params = [spec.build(point_values(spec, point, speed=s)).p for s in point["approach"]]
    chain = list(continuation.natural(spec, params, dop853(1e-10), cold_guess=spec.cold_guess, tol=1e-9,
                                 transient_periods=50))
    if chain[-1].status != 0:
        raise RuntimeError(f"no orbit on the approach to {point['name']}")
    return chain[-1].state, 1.0, None, None


def _backbone_start(spec, point, built):
    """(state, period, j, amplitude), scaled, from the backbone continued up to the amplitude."""
    v = point_values(spec, point)
    bb = follow_backbone(spec, v, dop853(1e-12), point["mode"], point["amplitude"], Settings(tol=1e-11))
    scale = spec.to_physical(np.ones(spec.n_state), built.period)
    k = int(np.argmin(np.abs(bb.amplitude - point["amplitude"])))
    return bb.states[k] / scale, bb.period[k] / built.period, bb.coordinate, point["amplitude"] / spec.length_scale


def prepare_peer(spec, point):
    """(the point's scipy peer, its kernel parameter vector)."""
    v = point_values(spec, point)
    built = spec.build(v)
    if spec.forced:
        return RigidPreloadedPeer(_rigid_params(built.p)), built.p
    return SeriesRotorPeer(spec.polynomial(v), built.period, spec.length_scale), built.p


def prepare(point, ref_rtol, check_rtol):
    """The point's kernel inputs, its peer and its reference solution (our solver at ref_rtol),
    with two estimates of the reference's error: ours at check_rtol, scipy at ref_rtol."""
    spec = models.get(point["model"])
    built = spec.build(point_values(spec, point))
    forced = spec.forced
    ref = dict(spec=spec, p=built.p, forced=forced, period_s=built.period, peer=prepare_peer(spec, point)[0])
    if forced:
        s0, period, ref["j"], ref["amplitude"] = _forced_start(spec, point)
        ours, peer = ours_forced, peer_forced
    else:
        s0, period, ref["j"], ref["amplitude"] = _backbone_start(spec, point, built)
        ours, peer = ours_autonomous, peer_autonomous
    ref["period_guess"] = period
    out = ours(ref, ref_rtol, s0, ref_rtol * 10)
    ref.update(state=out[0], period=out[1], multipliers=out[2], ref_converged=bool(out[5]))
    # the start of the timed solves and of the checks: state times (1 +- 1 %), period +0.1 %
    ref["start"] = out[0] * (1.0 + 0.01 * (-1.0) ** np.arange(out[0].size))
    ref["period_guess"] = 1.0 if forced else out[1] * (1.0 + 1e-3)
    checks = {"ours": ours(ref, check_rtol, ref["start"], ref_rtol * 10),
              "scipy": peer(ref, ref_rtol, ref["start"], ref_rtol * 10)}
    ref["checks"] = {k: _errors(ref, c) for k, c in checks.items()}
    ref["error_state"] = max(c["err_state"] for c in ref["checks"].values())
    ref["error_mult"] = max(c["err_mult"] for c in ref["checks"].values())
    ref["error_period"] = max(c["err_period"] for c in ref["checks"].values())
    return ref


def record(ref):
    """The reference as JSON."""
    return dict(state=[float(x) for x in ref["state"]], period=float(ref["period"]), period_s=float(ref["period_s"]),
                multipliers=complex_list(ref["multipliers"]), max_abs=float(np.abs(ref["multipliers"]).max()),
                j=ref["j"], amplitude=ref["amplitude"], converged=ref["ref_converged"], checks=ref["checks"],
                error_state=ref["error_state"], error_mult=ref["error_mult"], error_period=ref["error_period"])


def solve_rows(ref, rtols, repeats):
    """One row per rtol: ours and scipy from the reference's start, errors, right-hand sides and times (each
    scipy call followed by 10 of ours: both see the same machine state)."""
    ours, peer = (ours_forced, peer_forced) if ref["forced"] else (ours_autonomous, peer_autonomous)
    rows, guess = [], ref["start"]
    for rtol in rtols:
        tol = rtol / 10
        counted = ours(ref, rtol, guess, tol) if ref["forced"] else ours(ref, rtol, guess, tol, _Counting)
        t_peer, t_cpu, (t_ours,), (t_ours_cpu,) = time_pair(lambda: peer(ref, rtol, guess, tol),
                                                            (lambda: ours(ref, rtol, guess, tol),), repeats)
        rows.append(dict(rtol=rtol, atol=rtol * 1e-2, newton_tol=tol, t_scipy=t_peer, t_scipy_cpu=t_cpu,
                         t_ours=t_ours, t_ours_cpu=t_ours_cpu, ratio=t_peer / t_ours, ratio_cpu=t_cpu / t_ours_cpu,
                         ours=_errors(ref, counted), scipy=_errors(ref, peer(ref, rtol, guess, tol))))
    return rows
