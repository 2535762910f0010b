"""The jitted functions the attractor diagnostics call from Python, each with example arguments
of the types they pass, so that a warm-up compiles exactly those (`rotorsweep.pipeline.warmup`); each module
lists its own next to its calls."""
from rotorsweep.kernels.attractor.lyapunov import entry_points as lyapunov_entry_points
from rotorsweep.kernels.attractor.period import entry_points as period_entry_points
from rotorsweep.kernels.attractor.poincare import entry_points as poincare_entry_points


def entry_points(spec, opts):
    """(jitted function, example arguments) of each kernel `diagnose` calls for model `spec` with
    integrator settings `opts`; none for a conservative model (no forcing period to sample)."""
    if not spec.forced:
        return []
    kernel = spec.kernel
    return poincare_entry_points(kernel, opts) + lyapunov_entry_points(kernel, opts) + period_entry_points(spec.n_state)
