"""The scipy peer in the same run: scipy `solve_ivp` (DOP853 and LSODA) doing the same shooting
the way a user would, timed against our solve at the same settings and at matched accuracy."""
import time

import numpy as np

from workflows.bench import jeffcott as jc
from workflows.bench.common import best_time, log
from workflows.bench.peers.jeffcott_scipy import ScipyPeer
from workflows.bench.references import from_complex_list, match, state_error
from workflows.bench.scene import ATOL_OVER_RTOL, GUESS_PERTURBATION, newton_tol


def interp_time(rows, accuracy):
    """Our DOP853 time per orbit solve at `accuracy`, interpolated log-log along our work-precision
    curve (accuracy of a setting: max of its median-over-starts orbit and multiplier errors), made
    monotone (the cost of reaching an accuracy is that of the cheapest setting at least that
    accurate) and clamped at its ends. Returns (time, inside the measured range)."""
    pts = sorted((max(r["err_orbit_med"], r["err_mult_med"]), r["t_orbit"]) for r in rows
                 if r["method"] == "dop853" and r["status"] == 0)
    acc = np.log10(np.maximum([a for a, _ in pts], 1e-17))
    t = np.minimum.accumulate(np.log10([t for _, t in pts]))
    x = np.log10(max(accuracy, 1e-17))
    return float(10 ** np.interp(x, acc, t)), bool(acc[0] <= x <= acc[-1])


def _peer_point(peer, guess, method, rtol, tol):
    """The scipy user's point: shooting with solve_ivp, then the multipliers (numpy eigvals)."""
    out = peer.shoot(guess, method, rtol, rtol * ATOL_OVER_RTOL, tol)
    return out, jc.multipliers(out[1])


def time_pair(peer_call, ours_calls, repeats):
    """(best wall, best CPU seconds of the peer call, best wall and best CPU seconds of each of
    ours_calls, as lists): each peer call is followed by 10 of each of ours, so that all see the
    same machine state."""
    t = t_cpu = np.inf
    t_ours, t_ours_cpu = [np.inf] * len(ours_calls), [np.inf] * len(ours_calls)
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        peer_call()
        t = min(t, time.perf_counter() - w0)
        t_cpu = min(t_cpu, time.process_time() - c0)
        for k, ours_call in enumerate(ours_calls):
            for _ in range(10):
                w0, c0 = time.perf_counter(), time.process_time()
                ours_call()
                t_ours[k] = min(t_ours[k], time.perf_counter() - w0)
                t_ours_cpu[k] = min(t_ours_cpu[k], time.process_time() - c0)
    return t, t_cpu, t_ours, t_ours_cpu


def _peer_row(e, peer, ours, method, rtol, repeats):
    p, s_ref = np.array(e["p"]), np.array(e["state"])
    guess = s_ref * (1.0 + GUESS_PERTURBATION)
    tol = newton_tol("dop853", rtol)
    ours_opts = jc.dop853(rtol, rtol * ATOL_OVER_RTOL)
    (s, mono, its, nfev, conv), _ = _peer_point(peer, guess, method, rtol, tol)
    lam_ref = from_complex_list(e["multipliers"])
    plain, lam_plain = jc.point(p, guess, ours_opts, tol, staged=False)
    t, t_cpu, (t_adj, t_plain), _ = time_pair(
        lambda: _peer_point(peer, guess, method, rtol, tol),
        (lambda: jc.point(p, guess, ours_opts, tol), lambda: jc.point(p, guess, ours_opts, tol, staged=False)),
        repeats)
    err_o, err_m = state_error(s, s_ref), match(jc.multipliers(mono), lam_ref)
    same = next((r for r in ours if r["method"] == "dop853" and r["value"] == rtol), None)
    t_match, inside = interp_time(ours, max(err_o, err_m))
    return dict(point=e["name"], method=method, rtol=rtol, t=t, t_cpu=t_cpu, iterations=its,
                nfev=int(nfev), converged=conv, err_orbit=err_o, err_mult=err_m, t_ours_same=t_adj,
                t_ours_wp=same["t_orbit"] if same else np.nan,
                ours_same_err_orbit=same["err_orbit"] if same else np.nan,
                ours_same_err_mult=same["err_mult"] if same else np.nan,
                n_rhs_ours_same=same["n_rhs_orbit"] if same else 0,
                t_ours_plain=t_plain, n_rhs_ours_plain=int(plain.n_rhs), ours_plain_converged=plain.status == jc.CONVERGED,
                ours_plain_err_orbit=state_error(plain.state, s_ref), ours_plain_err_mult=match(lam_plain, lam_ref),
                t_ours_matched=t_match, matched_inside=inside)


def peer_baseline(refs, wp_rows, methods, rtols, repeats):
    """One row per point, scipy method and rtol."""
    rows = []
    for e in refs["points"]:
        peer = ScipyPeer(jc.named_params(np.array(e["p"])))
        ours = [r for r in wp_rows if r["point"] == e["name"]]
        rows += [_peer_row(e, peer, ours, method, rtol, repeats) for method in methods for rtol in rtols]
        log(f"  scipy peer {e['name']}: done")
    return rows


def finite_difference_check(e, rtol=1e-8):
    """The peer with the monodromy by finite differences against the augmented system, at one
    point: why the augmented system is the baseline."""
    s_ref = np.array(e["state"])
    guess = s_ref * (1.0 + GUESS_PERTURBATION)
    peer = ScipyPeer(jc.named_params(np.array(e["p"])))
    args = (guess, "DOP853", rtol, rtol * ATOL_OVER_RTOL, newton_tol("dop853", rtol))
    t_aug, out_aug = best_time(lambda: peer.shoot(*args), 2, 0)
    t_fd, out_fd = best_time(lambda: peer.shoot_fd(*args), 2, 0)
    lam_ref = from_complex_list(e["multipliers"])
    return dict(point=e["name"], rtol=rtol, t_aug=t_aug, t_fd=t_fd,
                err_mult_aug=match(jc.multipliers(out_aug[1]), lam_ref),
                err_mult_fd=match(jc.multipliers(out_fd[1]), lam_ref),
                nfev_aug=out_aug[3], nfev_fd=out_fd[3])
