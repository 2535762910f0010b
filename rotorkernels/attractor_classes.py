"""The attractor classes a point's diagnosis (`attractor.diagnose`) ends in, the cube's `attractor`
flags: outside the `attractor` package, whose modules import Numba, so that reading a result
(`pipeline.schema`) needs none (issue 35)."""

# not_settled: the samples neither repeat nor form a torus and the exponent is negative -- the
# transient budget ran out before the state settled (a period longer than max_period, or
# critical slowing down next to a bifurcation); integration_failed: the integrator could not keep
# its tolerance (step-size underflow), which is not a divergence of the rotor.
ATTRACTOR = ("not_computed", "periodic", "quasi_periodic", "chaotic", "diverged", "not_settled",
             "integration_failed")
NOT_COMPUTED, PERIODIC, QUASI_PERIODIC, CHAOTIC, DIVERGED, NOT_SETTLED, INTEGRATION_FAILED = range(7)
