"""A point given on the command line (`point`, `--at`, `modes`): its values from flags with units,
checked against the scene's model as a sweep axis's values are (pipeline/config.py)."""
from rotorsweep.pipeline import units
from rotorsweep.pipeline.config import ConfigError, check_number, key_help, model_schema
from rotorsweep.kernels import models


def check_point(point, data):
    """Validate a single point (the `point` command): the model's sweep-axis rules and its own
    checks with the point's values (e.g. the clearance bound of the scene's bearing)."""
    spec = models.get(data["scene"]["model"])
    _, axis_keys = model_schema(spec)
    errors = []
    for name, key in axis_keys.items():
        v = point.get(name)
        if v is None:
            continue
        problem = check_number(float(v), key)
        if problem:
            errors.append(f"{name}: {problem}{key_help(key)}")
    if not errors and spec.check:
        errors = spec.check(data, {k: [float(v)] for k, v in point.items() if v is not None})
    if errors:
        raise ConfigError("\n".join(errors))


def flag_values(flags, spec, unit_of=None):
    """{axis: value} from CLI flags {axis: (flag, text)}: units.flag_values, its problems as a
    ConfigError."""
    try:
        return units.flag_values(flags, spec, unit_of)
    except units.UnitError as exc:
        raise ConfigError(str(exc)) from None
