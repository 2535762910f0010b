"""The codes a continuation records (how a branch ended, which event was located), the result's
`branch_end` and `event_type` flags: outside the `continuation` package, whose modules import
Numba, so that reading a continuation result (`info`, `query`) needs none (issue 35)."""

# How a branch ended (the result's `end` code), one vocabulary for every problem.
END_REASONS = (
    "left_range",          # reached an edge of the parameter range (success)
    "step_budget",         # max_steps points computed
    "newton_failed",       # the corrector did not converge even at the minimum step
    "integration_failed",  # the flow diverged (NaN, amplitude limit) even at the minimum step
    "start_failed",        # no solution at the starting point
    "rejoined",            # a switched (period-2k) branch met its period-k parent again
    "closed_loop",         # the branch came back to its first point (an isola, a period-doubling bubble)
    "torus_breakdown",     # an invariant torus lost its smoothness (its Fourier decay failed: continuation.tori)
)
LEFT_RANGE, STEP_BUDGET, NEWTON_FAILED, INTEGRATION_FAILED, START_FAILED, REJOINED, CLOSED_LOOP, TORUS_BREAKDOWN = range(8)

# The bifurcations of orbits located on a branch (the codes a branch's events record).
# The last three are events of torus branches (continuation.tori): a change of normal stability, a
# fold of tori (flags between two points) and a locked ratio (a periodic orbit on the torus).
EVENT_TYPES = ("fold", "period_doubling", "neimark_sacker", "branch_point", "peak",
               "torus_stability", "torus_fold", "locked")
FOLD, PERIOD_DOUBLING, NEIMARK_SACKER, BRANCH_POINT, PEAK, TORUS_STABILITY, TORUS_FOLD, LOCKED = range(8)
EVENT_LABELS = ("LP", "PD", "NS", "BP", "PK", "TS", "TF", "locked")
