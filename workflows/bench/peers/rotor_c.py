"""The C floor of the rotor models (rotor_rhs.c: rigid_preloaded's ball sums, the series rotors'
cubic law, gcc -O3 -march=native, no fast-math): cost per right-hand side and per variational
derivative over given states, and the values themselves for checking them against the kernels."""
import subprocess
from pathlib import Path

import numpy as np

from workflows.bench.peers.jeffcott_c import CFloor

SOURCE = Path(__file__).with_name("rotor_rhs.c")
MODELS = ("rigid_preloaded", "symmetric4", "asymmetric5")


class RotorCFloor(CFloor):
    """rotor_rhs.c compiled in a temporary directory (a context manager, see CFloor)."""

    def __init__(self):
        super().__init__(SOURCE)

    def _write(self, path, p, taus, states, phi):
        with open(path, "wb") as f:
            np.array([len(taus), len(p)], np.int64).tofile(f)
            for a in (p, taus, states, phi):
                np.ascontiguousarray(a, np.float64).tofile(f)

    def _run(self, model, p, taus, states, phi, passes, out=None):
        if model not in MODELS:
            raise ValueError(f"no C floor for {model!r}; there is one for {', '.join(MODELS)}")
        data = self.dir / f"{model}.bin"
        self._write(data, p, taus, states, phi)
        args = [str(self.exe), model, str(data), str(passes)] + ([str(out)] if out else [])
        res = subprocess.run(args, capture_output=True, text=True, check=True)
        return [float(v) for v in res.stdout.split()]

    def measure(self, model, p, taus, states, phi, passes):
        """(ns per rhs, checksum, ns per variational derivative, checksum): best of `passes`
        passes over the states; every variational evaluation uses the tangent matrix phi."""
        return tuple(self._run(model, p, taus, states, phi, passes))

    def values(self, model, p, taus, states, phi):
        """(f per state (k, n), [f, J phi] per state (k, n + n^2)) as the C code computes them."""
        out = self.dir / f"{model}.out"
        self._run(model, p, taus, states, phi, 1, out)
        k, n = states.shape
        raw = np.fromfile(out, np.float64)
        return raw[:k * n].reshape(k, n), raw[k * n:].reshape(k, n + n * n)
