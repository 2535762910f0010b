"""The shipped scenes: the paper configs (configs/*.toml in the repository), installed as the
package data of `rotorsweep.scenes`, so that a pip-installed user has them too.

`rotorsweep scenes` lists them (name and the first sentence of the file's header comment),
`rotorsweep run NAME` (and every command taking a config) runs one when no file NAME exists,
`rotorsweep scenes --copy NAME [DEST]` copies one to edit.
"""
import re
import shutil
from importlib import resources
from pathlib import Path

from rotorsweep.pipeline.config import ConfigError

# A full stop after these is not the end of a header's first sentence ("Figs. 5-6", "eq. 14").
_ABBREVIATIONS = ("Fig", "Figs", "eq", "eqs", "Eq", "e.g", "i.e", "cf", "vs", "al", "No")
DESCRIPTION_CHARS = 80


def scene_dir():
    """The directory holding the shipped scenes (site-packages/rotorsweep/scenes, or the
    checkout's configs/ in an editable install)."""
    return Path(str(resources.files("rotorsweep.scenes")))


def names():
    """The shipped scenes' names (file names without .toml), sorted."""
    return sorted(p.stem for p in scene_dir().glob("*.toml"))


def path_of(name):
    """The file of the shipped scene `name` (with or without .toml), or None."""
    stem = name[:-len(".toml")] if name.endswith(".toml") else name
    return scene_dir() / f"{stem}.toml" if stem in names() else None


def description(text):
    """The first sentence of a scene's header comment (its leading `#` lines), cut to
    DESCRIPTION_CHARS; "" without a header."""
    header = []
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        header.append(line.lstrip("#").strip())
    words = " ".join(header).split()
    sentence = []
    for word in words:
        sentence.append(word)
        if word.endswith(".") and word.rstrip(".") not in _ABBREVIATIONS:
            break
    first = " ".join(sentence)
    return first if len(first) <= DESCRIPTION_CHARS else first[:DESCRIPTION_CHARS - 3].rstrip() + "..."


def listing():
    """[(name, description)] of every shipped scene."""
    return [(name, description(path_of(name).read_text(encoding="utf-8"))) for name in names()]


def resolve(config):
    """A config path as given when such a file exists, else the shipped scene of that name;
    ConfigError naming the shipped scenes when neither exists."""
    if Path(config).exists():
        return config
    shipped = path_of(str(config)) if re.fullmatch(r"[\w.-]+", str(config)) else None
    if shipped is None:
        raise ConfigError(f"{config}: no such config file, nor a shipped scene of that name "
                          f"(`rotorsweep scenes` lists them: {', '.join(names())})")
    return str(shipped)


def copy(name, dest=None, overwrite=False):
    """Copy the shipped scene `name` to dest (a file, or a directory to copy into; default
    ./NAME.toml); returns the path written. An existing file is kept unless overwrite."""
    source = path_of(name)
    if source is None:
        raise ConfigError(f"{name}: no shipped scene of that name (`rotorsweep scenes` lists them: "
                          f"{', '.join(names())})")
    target = Path(dest) if dest is not None else Path(source.name)
    if target.is_dir():
        target = target / source.name
    if target.exists() and not overwrite:
        raise ConfigError(f"{target}: exists; pass --overwrite to replace it")
    shutil.copyfile(source, target)
    return target
