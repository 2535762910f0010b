"""The C floor: the scaled Jeffcott/Bai right-hand side in plain C (jeffcott_rhs.c, gcc -O3
-march=native, no fast-math), timed per evaluation over given states."""
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

SOURCE = Path(__file__).with_name("jeffcott_rhs.c")
FLAGS = ("-O3", "-march=native", "-std=c11")


class CFloor:
    """The compiled C program in a temporary directory (a context manager). `compiler` is the
    command line when it compiled, else None and `skipped` says why. `source`: the C file (the
    Jeffcott one by default; `rotor_c` compiles another with this class)."""

    def __init__(self, source=SOURCE):
        self.source = source

    def __enter__(self):
        self._tmp = tempfile.TemporaryDirectory(prefix="rotorsweep-bench-")
        self.dir = Path(self._tmp.name)
        self.exe = self.dir / "rhs_floor"
        self.compiler, self.skipped = None, None
        gcc = shutil.which("gcc")
        if gcc is None:
            self.skipped = "gcc not found: C floor skipped"
            return self
        proc = subprocess.run([gcc, *FLAGS, "-o", str(self.exe), str(self.source), "-lm"],
                              capture_output=True, text=True)
        if proc.returncode != 0:
            self.skipped = f"gcc failed: {proc.stderr.strip()[:300]}"
        else:
            self.compiler = " ".join(["gcc", *FLAGS, "-lm"])
        return self

    def __exit__(self, *exc):
        self._tmp.cleanup()

    def measure(self, name, p, taus, states, passes):
        """(ns per rhs, checksum, ns per variational derivative, checksum): best of `passes`
        passes over the states (p: the kernels' parameter vector)."""
        data = self.dir / f"{name}.bin"
        with open(data, "wb") as f:
            np.array([len(taus)], np.int64).tofile(f)
            np.asarray(p, np.float64).tofile(f)
            np.asarray(taus, np.float64).tofile(f)
            np.ascontiguousarray(states, np.float64).tofile(f)
        res = subprocess.run([str(self.exe), str(data), str(passes)], capture_output=True, text=True)
        rhs_ns, rhs_sum, var_ns, var_sum = (float(v) for v in res.stdout.split())
        return rhs_ns, rhs_sum, var_ns, var_sum
