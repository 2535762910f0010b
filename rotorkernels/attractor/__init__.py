"""Attractor diagnostics from a long run after a transient: stroboscopic Poincare samples
(`poincare`), period-k detection (`period`), Lyapunov exponents by Benettin with QR
(`lyapunov`), power spectrum, and one point's classification (`diagnosis`).

Everything works in the models' scaled time tau = t / T (the forcing period is 1), so the
kernels return exponents *per unit tau* (per forcing period); `lyapunov_si` divides by T to give
1/s. Pure numerics: arrays in, arrays out, failures as status codes (the integrators' STATUS_*).
"""
from rotorsweep.kernels.attractor.compiled import entry_points  # noqa: F401
from rotorsweep.kernels.attractor.diagnosis import (  # noqa: F401 (the package's API)
    ATTRACTOR, CHAOTIC, DIVERGED, INTEGRATION_FAILED, LLE_FLOOR, NOT_COMPUTED, NOT_SETTLED, PERIODIC,
    QUASI_PERIODIC, SIGMAS, Attractor, Settings, classify, failure_class, closed_curve, diagnose, exponents_of_orbit, periodic_orbit_of,
    settle_on_continued_orbit, settle_on_orbit, settle_periodic)
from rotorsweep.kernels.attractor.lyapunov import (  # noqa: F401
    Lyapunov, derived_lle, largest_lyapunov, lyapunov_si, lyapunov_spectrum)
from rotorsweep.kernels.attractor.period import PERIOD_FLOOR, default_period_rtol, detect_period  # noqa: F401
from rotorsweep.kernels.attractor.poincare import poincare, power_spectrum  # noqa: F401
