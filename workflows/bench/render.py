"""Markdown from templates: templates/<name>.md with string.Template placeholders, and
templates/<name>_parts.md holding the optional pieces, each after a `<!-- part: key -->` line."""
import re
from functools import lru_cache
from pathlib import Path
from string import Template

TEMPLATES = Path(__file__).with_name("templates")
_PART = re.compile(r"^<!-- part: (\w+) -->\n", re.MULTILINE)


def fill(name, **values):
    """templates/<name>.md with its placeholders filled (a missing value is an error)."""
    return Template((TEMPLATES / f"{name}.md").read_text()).substitute(values)


@lru_cache(maxsize=None)
def _parts(name):
    chunks = _PART.split((TEMPLATES / f"{name}_parts.md").read_text())
    # chunks: [preamble, key, text, key, text, ...]; a part ends before the next marker's newline
    return {key: Template(text[:-1] if text.endswith("\n") else text)
            for key, text in zip(chunks[1::2], chunks[2::2])}


def part(name, key, **values):
    """The part `key` of templates/<name>_parts.md, filled."""
    return _parts(name)[key].substitute(values)


def table(header, rows):
    """A markdown table, every column left-aligned."""
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(" --- " for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)
