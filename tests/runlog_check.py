"""The log file a command writes next to its output (rotorsweep.pipeline.runlog): what the tests of `run`,
`continue` and `backbone` check in it."""
import re
from pathlib import Path

# a record: a timestamp, then "== " for a phase line
RECORD = re.compile(r"^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d (== )?.+$")


def check_log(output, command, phases, progress_unit):
    """The log of `command` at <output>.log: every line a timestamped record, opened by the
    command's line, the phase lines in order, a progress line in `progress_unit`, closed by the
    wall time. Returns the log's lines."""
    lines = Path(f"{output}.log").read_text().splitlines()
    assert lines and all(RECORD.match(line) for line in lines), lines
    assert lines[0].endswith(f"rotorsweep {command} -> {output}") and " done in " in lines[-1], lines
    found = [next((i for i, line in enumerate(lines) if f" == {phase}" in line), None) for phase in phases]
    assert None not in found and found == sorted(found), (phases, lines)
    assert any(f" {progress_unit}/s " in line and " == " not in line for line in lines), lines
    return lines
