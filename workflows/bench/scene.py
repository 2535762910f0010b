"""The kernel benchmarks' scene: the Bai 2006 rotor, its reference points and the integrator
settings compared. Plain data (no kernel imports), shared by measurement and rendering."""
import numpy as np

# Bai 2006: M = 2 kg, D = 300 N s/m, K = 2.883e9 N/m^1.5, W = M g (g = 9.8), the 209 bearing.
BAI = dict(mass=2.0, damping=300.0, stiffness=2.883e9, radial_load=2.0 * 9.8, n_balls=9,
           ball_diameter=12.7e-3, pitch_diameter=65.0e-3, groove_radius_inner=6.6e-3,
           groove_radius_outer=6.6e-3)


def contact_angle(clearance):
    """Free contact angle, Bai 2006 eq. 6: cos a = 1 - c / (r_i + r_o - D_b)."""
    groove = BAI["groove_radius_inner"] + BAI["groove_radius_outer"] - BAI["ball_diameter"]
    return float(np.arccos(1.0 - clearance / groove))


# The reference points. `approach`: speeds of a short continuation chain that selects the branch
# (the one a speed sweep follows); the last entry is the point itself.
POINTS = [
    dict(name="stable", speed=60.0, clearance=3.8e-6, approach=[60.0],
         kind="stable period-1 orbit"),
    dict(name="near_pd", speed=80.85, clearance=7.6e-6, approach=[78.0, 80.0, 80.85],
         kind="just below period doubling (real multiplier near -1)"),
    dict(name="near_ns", speed=130.0, clearance=11.4e-6, approach=[125.0, 128.0, 130.0],
         kind="just past Neimark-Sacker (complex pair, |lambda| ~ 1.0006)"),
    dict(name="chaotic", speed=30.0, clearance=19.0e-6, approach=[25.0, 27.5, 30.0],
         kind="unstable period-1 orbit inside a chaotic attractor"),
]
# Stability boundary used for the boundary work-precision: the period-doubling crossing at
# 7.6 um between these two speeds (Hz); errors are also taken over the other brackets.
BOUNDARY = dict(clearance=7.6e-6, bracket=(80.0, 82.0))
BOUNDARY_BRACKETS = [(80.0, 82.0), (79.0, 83.0), (80.5, 81.5)]

# Newton starts of the orbit-solve benchmark: the reference state times (1 + 0.01 * pattern).
# The first pattern is the timed start; the errors are also taken over all eight, because the
# error of one DOP853 run depends on where its steps fall relative to the contact switching times
# (see STEP_PLACEMENTS), and different starts give different step sequences.
START_PATTERNS = np.array([[1, -1, 1, -1], [1, 1, 1, 1], [-1, -1, -1, -1], [1, -1, -1, 1],
                           [-1, 1, 1, -1], [1, 1, -1, -1], [-1, -1, 1, 1], [-1, 1, -1, 1]], float)
GUESS_PERTURBATION = 0.01 * START_PATTERNS[0]
# Initial step sizes h0 (scaled time) of the monodromy runs: h0 = 0 (the integrator's own start,
# 0.01) is the timed run; the others shift the whole step sequence relative to the instants where
# a ball enters contact. A step that straddles such an instant sees the square-root kink of the
# Jacobian (dQ/ddelta = 1.5 delta^1/2), which the embedded error estimate can miss: the error of a
# single monodromy scatters over orders of magnitude with the placement (heavy tail).
STEP_PLACEMENTS = np.concatenate([[0.0], np.geomspace(1e-5, 1e-2, 15)])
REF_STEP_PLACEMENTS = np.concatenate([[0.0], np.geomspace(1e-6, 3e-2, 39)])

REF_RTOL, REF_ATOL, REF_NEWTON_TOL = 1e-13, 1e-15, 1e-13
CHECK_RTOL, CHECK_ATOL = 1e-14, 1e-16
CHECK_RK4_STEPS = (2 ** 15, 2 ** 16, 2 ** 17)
REF_CHECK_KEY = "dop853 rtol=1e-14 atol=1e-16"

DOP_RTOLS_FULL = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
RK4_STEPS_FULL = (64, 128, 256, 512, 1024, 2048, 4096)
DOP_RTOLS_QUICK = (1e-6, 1e-8, 1e-10, 1e-12)
RK4_STEPS_QUICK = (128, 512, 2048)
ATOL_OVER_RTOL = 1e-2          # atol = rtol / 100, the ratio of the config default (1e-10, 1e-12)
DEFAULT_LABEL = "dop853 rtol=1e-10"   # the configs' default: dop853, rtol 1e-10, atol 1e-12
HEADLINE_RTOL = 1e-10          # the peer comparison of the headline: the config default's rtol
TARGETS = (1e-6, 1e-8)
# Recommended settings: (key, error key, time key) of the rows the cheapest setting is chosen from.
REC_QUANTITIES = (("orbit", "err_orbit_max", "t_orbit"), ("mult", "err_mult_max", "t_orbit"),
                  ("mult_typ", "err_mult_med", "t_orbit"), ("mono", "err_mono_max", "t_mono"),
                  ("mono_typ", "err_mono_med", "t_mono"), ("boundary", "err_max", "t"))


def rec_key(key, target):
    """Key of a recommendation in results.json, e.g. 'mult 1e-08'."""
    return f"{key} {target:.0e}"


def newton_tol(method, value):
    """Newton tolerance used with an integrator setting.

    DOP853: rtol / 10. The return map of an adaptive integrator is smooth only to about 1e-3 rtol
    (the step sequence changes between Newton iterations), so a much tighter Newton tolerance
    stalls in the line search (measured: rtol 1e-8 with tol 1e-11 fails). RK4 (a fixed step
    sequence, smooth map): 1e-12."""
    return 0.1 * value if method == "dop853" else 1e-12


def setting_label(method, value):
    return f"dop853 rtol={value:.0e}" if method == "dop853" else f"rk4 {int(value)} steps"
