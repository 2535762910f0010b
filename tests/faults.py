"""Faults the reliability tests inject, written once."""
from rotorsweep.pipeline import cube


def disk_full_after_one_part(monkeypatch):
    """cube.write_part writes its first part, then every later one fails as a full disk would."""
    write_part = cube.write_part
    written = []

    def full_after_one(parts_dir, chunk_id, *rest):
        if written:
            raise OSError(28, "No space left on device", str(parts_dir / f"{chunk_id}.npz"))
        written.append(chunk_id)
        return write_part(parts_dir, chunk_id, *rest)

    monkeypatch.setattr(cube, "write_part", full_after_one)
