"""A synthetic result cube that follows rotorsweep.pipeline.schema, for tests of query/report/cube code
that must not wait for a real sweep. Values are made up but shaped like a Fig. 13 sweep:
unstable speed bands whose position depends on clearance, with all three instability types.

attractor=True adds the attractor diagnostics of a sweep ([analysis] attractor = true: a
period-doubling cascade into chaos on the period-doubling lines, see attractor_variables);
sweep_direction="both" adds the down sweep (`_down`) and `hysteresis`; boundaries=True adds a
boundary table (add_boundary_table)."""
import numpy as np
import xarray as xr

from rotorsweep.pipeline import cube, schema
from rotorsweep.kernels.models.jeffcott_clearance import SPEC as JEFFCOTT

JEFFCOTT_VARIABLES = schema.variables_of(schema.model_of({}))


def synthetic_cube(speed=None, clearance=None, n_multipliers=4, attractor=False,
                   sweep_direction="up", boundaries=False, n_samples=128):
    speed = np.round(np.arange(10.0, 250.01, 2.0), 6) if speed is None else np.asarray(speed, float)
    clearance = np.array([3.8e-6, 7.6e-6, 11.4e-6, 15.2e-6, 19.0e-6]) if clearance is None else np.asarray(clearance, float)
    S, C = np.meshgrid(speed, clearance, indexing="ij")
    centre = 60.0 + 8e6 * C                   # band centre moves with clearance
    mu = 0.6 + 0.6 * np.exp(-(((S - centre) / 15.0) ** 2))
    mu = np.where(C > 15e-6, mu + 0.3 * (S > 200), mu)
    kind = np.where(C < 8e-6, 2, np.where(C < 16e-6, 3, 1)).astype("int8")
    stable = (mu < 1).astype("int8")
    shape = S.shape
    data = {
        "orbit_status": np.zeros(shape, "int8"),
        "orbit_reason": np.zeros(shape, "int8"),
        "newton_iterations": np.full(shape, 3, "int16"),
        "residual": np.full(shape, 1e-12),
        "max_abs_multiplier": mu,
        "stable": stable,
        "bifurcation": np.where(stable == 1, 0, kind).astype("int8"),
        "forcing_period": 1.0 / (S * 9 * 0.4),
        "contact_angle_used": np.degrees(np.arccos(1 - C / 0.5e-3)),
        "x_mean": np.zeros(shape),
        "y_mean": -1e-6 * np.ones(shape),
        "amplitude_x": 1e-7 * mu,
        "amplitude_y": 2e-7 * mu,
        "compute_time": np.full(shape, 1e-3),
    }
    angle = np.where(kind[..., None] == 3, 0.7, np.where(kind[..., None] == 2, np.pi, 0.0))
    k = np.arange(n_multipliers)
    lam = (mu[..., None] * (0.5 ** k)) * np.exp(1j * angle * np.where(k % 2 == 0, 1, -1))
    data["multiplier_real"] = lam.real
    data["multiplier_imag"] = lam.imag
    data["orbit_state"] = np.stack([data["x_mean"], data["y_mean"], 0 * mu, 0 * mu], axis=-1)
    if attractor:
        att = attractor_variables(S, C, mu, kind, stable, data["forcing_period"],
                                  n_samples=n_samples)
        data.update(att)
        if sweep_direction == "both":
            down, hyst = _hysteresis_window(att, stable, kind)
            data.update({name + schema.DOWN_SUFFIX: v for name, v in down.items()})
            data["hysteresis"] = hyst
    dims = ("speed", "clearance")
    ds = xr.Dataset(coords={
        "speed": ("speed", speed, {"units": "Hz", "long_name": "shaft speed"}),
        "clearance": ("clearance", clearance, {"units": "m", "long_name": "radial internal clearance"}),
        "multiplier": ("multiplier", k),
        "state": ("state", np.arange(4)),
        **({"sample": ("sample", np.arange(n_samples)), "exponent": ("exponent", np.arange(4))}
           if attractor else {}),
        "preload": ((), 0.0, {"units": "N", "long_name": "axial preload"}),
    })
    for name, values in data.items():
        extra, dtype, attrs = JEFFCOTT_VARIABLES[name]
        ds[name] = (dims + tuple(extra), np.asarray(values).astype(dtype), dict(attrs))
    ds.attrs.update({
        "Conventions": "CF-1.10",
        "title": "synthetic test cube",
        "rotorsweep_schema_version": schema.SCHEMA_VERSION,
        "config_toml": "[scene]\nname = \"synthetic\"\n",
        "config_hash": "0" * 64,
        cube.DERIVED_ATTR: f"contact_angle: {JEFFCOTT.derived_axes['contact_angle']}",
    })
    return add_boundary_table(ds) if boundaries else ds


# ----------------------------------------------------------------------------- attractor, boundaries

def add_boundary_table(ds):
    """ds with a boundary table (schema.BOUNDARY_VARIABLES): every stability change between
    neighbouring converged speeds of a clearance line, 'refined' by interpolating
    max |multiplier| = 1 linearly between the two grid speeds (so it lies strictly inside)."""
    speed = ds["speed"].values
    rows = []
    for c in ds["clearance"].values:
        line = ds.sel(clearance=c)
        mu, st = line["max_abs_multiplier"].values, line["stable"].values
        ok = line["orbit_status"].values == 0
        for i in range(speed.size - 1):
            if not (ok[i] and ok[i + 1]) or st[i] == st[i + 1]:
                continue
            t = (1.0 - mu[i]) / (mu[i + 1] - mu[i])
            unstable = i + 1 if st[i] == 1 else i
            rows.append({"boundary_speed": speed[i] + t * (speed[i + 1] - speed[i]),
                         "boundary_type": int(line["bifurcation"].values[unstable]),
                         "boundary_direction": 0 if st[i] == 1 else 1, "boundary_status": 0,
                         "boundary_grid_low": speed[i], "boundary_grid_high": speed[i + 1],
                         "boundary_clearance": float(c)})
    out = ds.copy()
    for name, (dtype, attrs) in schema.boundary_variables("speed", "Hz", "shaft speed").items():
        out[name] = ("boundary", np.array([r[name] for r in rows], dtype=dtype), dict(attrs))
    out["boundary_clearance"] = ("boundary", np.array([r["boundary_clearance"] for r in rows], float),
                                 {"units": "m", "long_name": "radial internal clearance of the boundary"})
    return out


GOLDEN = 0.5 * (np.sqrt(5.0) - 1.0)


def _logistic(r, x0, n_transient, n_samples):
    x = np.full(r.shape, x0)
    for _ in range(n_transient):
        x = r * x * (1 - x)
    out = np.empty(r.shape + (n_samples,))
    for j in range(n_samples):
        x = r * x * (1 - x)
        out[..., j] = x
    return out


def _period(samples, max_period, tol=1e-7):
    """Smallest k <= max_period with samples[k:] == samples[:-k] (to tol), 0 if none."""
    k = np.zeros(samples.shape[:-1], "int16")
    for p in range(max_period, 0, -1):
        same = np.abs(samples[..., p:] - samples[..., :-p]).max(axis=-1) < tol
        k = np.where(same, p, k)
    return k


def attractor_variables(S, C, mu, kind, stable, T, x0=0.3, n_samples=128, max_period=32):
    """Made-up but plausible attractor variables (schema.ATTRACTOR_VARIABLES without _down) over
    the (speed, clearance) grid. Period-doubling lines follow the logistic map with r = 3 at
    max |multiplier| = 1: period 1 where the orbit is stable, a period-doubling cascade into chaos
    (and back) across the unstable band. Neimark-Sacker lines go quasi-periodic (samples on a
    closed curve), fold lines jump to another stable period-1 orbit."""
    r = np.clip(3.0 + 4.5 * (mu - 1.0), 1.5, 3.97)
    xs = _logistic(r, x0, 3000, n_samples)
    period = _period(xs, max_period)
    factor = np.abs(r[..., None] * (1 - 2 * xs))
    lam = np.log(np.maximum(factor, 1e-300)).mean(axis=-1)       # per forcing period
    centre = 0.4e-6 * np.sin(S / 40.0) + 0.02 * C                  # period-1 position [m]
    px = centre[..., None] + 3e-6 * (xs - 2.0 / 3.0)
    pd = (kind == 2) | stable.astype(bool)
    chaotic = pd & (period == 0) & (lam > 0)
    cls = np.where(chaotic, 3, 1).astype("int8")
    lle = np.where(chaotic, lam / T, np.where(period == 1, np.log(mu) / T, lam / T))
    stderr = np.where(chaotic, 0.05 * np.abs(lle) + 1.0, 0.0)
    method = np.where(chaotic, 0, 1).astype("int8")
    k = np.where(period > 0, period, 1)[..., None]
    lam_k = np.exp(lam * k[..., 0])
    # Neimark-Sacker: a torus, samples on a closed curve around the unstable orbit
    ns = (kind == 3) & ~stable.astype(bool)
    rho = 1e-6 * np.sqrt(np.maximum(mu - 1.0, 0.0))
    theta = 2 * np.pi * GOLDEN * np.arange(n_samples)
    px = np.where(ns[..., None], centre[..., None] + rho[..., None] * np.cos(theta), px)
    cls = np.where(ns, 2, cls).astype("int8")
    period = np.where(ns, 0, period).astype("int16")
    lle = np.where(ns, 0.02 / T, lle)
    stderr = np.where(ns, 0.05 / T, stderr)
    method = np.where(ns, 0, method).astype("int8")
    # fold: the rotor settles on another (stable) period-1 orbit
    fold = (kind == 1) & ~stable.astype(bool)
    px = np.where(fold[..., None], centre[..., None] + 1.5e-6, px)
    period = np.where(fold, 1, period).astype("int16")
    lle = np.where(fold, np.log(0.8) / T, lle)
    lam_k = np.where(fold, 0.8, lam_k)
    periodic = cls == 1
    py = -1e-6 + 0.5 * (px - centre[..., None])
    if not periodic.all():
        py = np.where(ns[..., None], -1e-6 + rho[..., None] * np.sin(theta), py)
    mult = np.stack([lam_k, 0.5 * lam_k, 0.2 * lam_k, 0.1 * lam_k], axis=-1)
    mult = np.where(periodic[..., None] & (period > 0)[..., None], mult, np.nan)
    exps = np.stack([lle, np.minimum(lle, 0) - 40.0, np.full(lle.shape, -110.0),
                     np.full(lle.shape, -150.0)], axis=-1)
    return {
        "attractor": cls, "period": period, "lle": lle, "lle_stderr": stderr, "lle_method": method,
        "lyapunov_exponents": exps, "poincare_x": px, "poincare_y": py,
        "attractor_multiplier_real": mult, "attractor_multiplier_imag": np.where(np.isfinite(mult), 0.0, np.nan),
        "lyapunov_periods": np.where(method == 0, 500.0, 0.0),
        "attractor_state": np.stack([px[..., -1] * 1e6, py[..., -1] * 1e6, 0 * lle, 0 * lle], axis=-1),
    }


def _hysteresis_window(up, stable, kind, n=2):
    """Down-sweep variables: the up sweep's, except that sweeping down the rotor stays on the
    period-2 orbit for n stable speeds below each period-doubling band (coexisting attractors)."""
    down = {name: v.copy() for name, v in up.items()}
    hyst = np.zeros(stable.shape, "int8")
    for j in range(stable.shape[1]):
        for i in range(1, stable.shape[0]):
            if stable[i - 1, j] == 1 and stable[i, j] != 1 and kind[i, j] == 2:
                src = i
                for b in range(max(0, i - n), i):
                    for name in down:
                        down[name][b, j] = up[name][src, j]
                    hyst[b, j] = int(up["period"][src, j] != up["period"][b, j])
    return down, hyst


# ----------------------------------------------------------------------------- tori

TORUS_KINDS = {"stable": (0, 1, -2.0), "unstable": (0, 0, 3.0), "undecided": (0, 2, 0.0),
               "failed": (schema.TORUS_STATUS.index("fourier_decay_failed"), schema.INT_FILL, np.nan)}


def with_tori(ds, kinds):
    """ds with the torus variables of a quasi-periodically forced sweep (schema.TORUS_VARIABLES,
    rotorsweep.pipeline.torus_points): kinds (array over (speed, clearance) of "orbit" or a
    TORUS_KINDS key) marks each point a periodic one (its orbit kept) or a torus point
    (orbit_status not_applicable, no multipliers) that is stable / unstable / undecided
    (exponent -2, 3, 0 times 1 + speed / 1000 1/s) or failed (fourier_decay_failed, NaN values,
    amplitudes NaN). A torus point's amplitudes stay the cube's (its torus's half-swing)."""
    kinds = np.asarray(kinds, object)
    torus = kinds != "orbit"
    out = ds.copy()
    speed = out["speed"].values[:, None] * np.ones(kinds.shape)
    status = np.full(kinds.shape, schema.INT_FILL, "int8")
    stab = np.full(kinds.shape, schema.INT_FILL, "int8")
    exponent = np.full(kinds.shape, np.nan)
    for name, (st, sb, ex) in TORUS_KINDS.items():
        at = kinds == name
        status[at], stab[at], exponent[at] = st, sb, ex * (1 + speed[at] / 1000)
    at_torus, at_failed = (xr.DataArray(m, dims=("speed", "clearance")) for m in (torus, kinds == "failed"))
    out["orbit_status"] = out["orbit_status"].where(~at_torus, schema.ORBIT_STATUS.index("not_applicable"))
    for name in ("stable", "bifurcation"):        # as a sweep writes a point without orbit
        out[name] = out[name].where(~at_torus, schema.INT_FILL)
    for name in ("max_abs_multiplier", "multiplier_real", "multiplier_imag"):
        out[name] = out[name].where(~at_torus)
    failed = kinds == "failed"
    for name in ("amplitude_x", "amplitude_y"):
        out[name] = out[name].where(~at_failed)
    values = {"torus_status": status, "torus_stability": stab, "torus_exponent": exponent,
              "torus_exponent_error": np.where(torus, 1e-3, np.nan),
              "torus_rotation_number": np.where(torus, 1.6180339887, np.nan),
              "torus_modes": np.where(torus, 7, schema.INT_FILL), "torus_error": np.where(torus & ~failed, 1e-9, np.nan),
              "torus_amplitude_error": np.where(torus & ~failed, 1e-4, np.nan)}
    for name, v in values.items():
        _, dtype, attrs = schema.TORUS_VARIABLES[name]
        out[name] = (("speed", "clearance"), v.astype(dtype), dict(attrs))
    return out
