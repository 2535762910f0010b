"""Floquet multipliers from a monodromy matrix and how the leading one left the unit circle.

Codes match rotorsweep.pipeline.schema.BIFURCATION: none, fold (+1), period_doubling (-1),
neimark_sacker (complex pair)."""
import numpy as np

NONE, FOLD, PERIOD_DOUBLING, NEIMARK_SACKER = range(4)

# A multiplier whose imaginary part is below this fraction of its modulus is taken as real:
# eigenvalues of a real matrix come out exactly real or as exact conjugate pairs, so only
# round-off of a near-collision is at stake.
REAL_TOL = 1e-8


def multipliers(monodromy):
    """Eigenvalues of the monodromy, largest modulus first (ties: by angle, for determinism)."""
    lam = np.linalg.eigvals(np.asarray(monodromy, float))
    order = np.lexsort((np.angle(lam), -np.abs(lam)))
    return lam[order]


def crossing_type(lam):
    """The bifurcation a multiplier would cause on leaving the unit circle."""
    if abs(lam.imag) > REAL_TOL * abs(lam):
        return NEIMARK_SACKER
    return FOLD if lam.real > 0 else PERIOD_DOUBLING


def classify(lams):
    """(max |lambda|, stable, bifurcation code) for multipliers sorted by `multipliers`.

    `bifurcation` is NONE for a stable orbit, else the type of the leading multiplier."""
    lead = lams[0]
    max_abs = float(abs(lead))
    stable = max_abs < 1.0
    return max_abs, stable, NONE if stable else crossing_type(lead)
