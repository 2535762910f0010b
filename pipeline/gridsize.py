"""How large a sweep's cube is in memory, and whether a grid fits (config validation, preflight).

The cube is assembled in the driver's memory: the full-grid arrays, the Dataset's typed copy and
netCDF's write buffers hold it about three times over."""
import os

CUBE_COPIES_IN_MEMORY = 3
ORBIT_BYTES_PER_POINT = 512    # ~20 orbit and Floquet variables, mostly float64, <= 8 multipliers
ATTRACTOR_BYTES_PER_POINT = 512


def bytes_per_point(data):
    """Rough size of one grid point in the cube: the Poincare samples dominate with attractors."""
    ana = data["analysis"]
    if ana["attractor"] is not True:
        return ORBIT_BYTES_PER_POINT
    samples = ana["poincare_samples"] if isinstance(ana["poincare_samples"], int) else 4096
    directions = 2 if ana["sweep_direction"] == "both" else 1
    return ORBIT_BYTES_PER_POINT + directions * (ATTRACTOR_BYTES_PER_POINT + 2 * 8 * samples)


def memory_bytes():
    """This machine's physical memory."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def grid_size_problem(n, data, limit, allow_large):
    """(message, may_confirm) when a grid of n points is too large, else None. limit
    (numerics.max_points) is a guard against typos that --yes lifts; the memory cap is not,
    since such a run could only fail at its end, when the cube is assembled."""
    per_point = bytes_per_point(data)
    cap = memory_bytes() // (CUBE_COPIES_IN_MEMORY * per_point)
    if n > cap:
        return (f"sweep: the grid has {n} points; at most {cap} fit in this machine's memory "
                f"({memory_bytes() / 2**30:.0f} GiB: the cube needs ~{per_point} bytes per point and "
                f"is held ~{CUBE_COPIES_IN_MEMORY} times while it is assembled), even with --yes; "
                "split the sweep into several configs"), False
    if n > limit and not allow_large:
        return (f"sweep: the grid has {n} points, above numerics.max_points = {limit}; raise "
                "numerics.max_points or pass --yes"), True
    return None
