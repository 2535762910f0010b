"""A synthetic result cube that follows pipeline.schema, for tests of query/report/cube code
that must not wait for a real sweep. Values are made up but shaped like a Fig. 13 sweep:
unstable speed bands whose position depends on clearance, with all three instability types."""
import numpy as np
import xarray as xr

from pipeline import schema


def synthetic_cube(speed=None, clearance=None, n_multipliers=4):
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
    dims = ("speed", "clearance")
    ds = xr.Dataset(coords={
        "speed": ("speed", speed, {"units": "Hz", "long_name": "shaft speed"}),
        "clearance": ("clearance", clearance, {"units": "m", "long_name": "radial internal clearance"}),
        "multiplier": ("multiplier", k),
        "state": ("state", np.arange(4)),
        "contact_angle": ((), np.nan, {"units": "degree", "long_name": "bearing contact angle (from clearance)"}),
        "preload": ((), 0.0, {"units": "N", "long_name": "axial preload"}),
    })
    for name, values in data.items():
        extra, dtype, attrs = schema.VARIABLES[name]
        ds[name] = (dims + tuple(extra), np.asarray(values).astype(dtype), dict(attrs))
    ds.attrs.update({
        "Conventions": "CF-1.10",
        "title": "synthetic test cube",
        "rotorsweep_schema_version": schema.SCHEMA_VERSION,
        "config_toml": "[scene]\nname = \"synthetic\"\n",
        "config_hash": "0" * 64,
    })
    return ds
