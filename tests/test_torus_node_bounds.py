"""The node-count bounds of torus branches as scene keys ([continuation] torus_min_modes and
torus_max_modes, Fourier modes K of 2K + 1 nodes): validated with errors that name the key and
what is allowed, and carried into the branch's family (rotorsweep.pipeline.torus_branches)."""
import pytest

from rotorsweep.pipeline import config, continuation, torus_branches

SCENE = "configs/filipkovsky2016_fig2b_tori.toml"


def scene_text(**keys):
    """The torus scene with extra [continuation] keys."""
    extra = "".join(f"{k} = {v}\n" for k, v in keys.items())
    return open(SCENE).read().replace("[continuation]\n", "[continuation]\n" + extra, 1)


def test_the_defaults_are_the_former_fixed_bounds():
    """3 to 31 modes: the 7 and 63 nodes the branches were bounded by before the keys existed."""
    scene = config.parse_config(open(SCENE).read()).scene
    assert torus_branches.node_bounds(scene) == (7, 63)


def test_the_bounds_reach_the_branch_family():
    scene = config.parse_config(scene_text(torus_min_modes=7, torus_max_modes=15)).scene
    pl = continuation.plan(scene)
    family, _ = torus_branches.torus_family(scene, pl, pl.lines[0], 15)
    assert family.node_bounds == (15, 31)


@pytest.mark.parametrize("keys, message", [
    ({"torus_max_modes": 20}, "continuation.torus_max_modes: unknown value 20; allowed: 3, 7, 15, 31, 63"),
    ({"torus_min_modes": 1}, "continuation.torus_min_modes: unknown value 1; allowed: 3, 7, 15, 31, 63"),
    ({"torus_min_modes": 15, "torus_max_modes": 7},
     "continuation.torus_min_modes: must be <= continuation.torus_max_modes (7), got 15"),
])
def test_bad_bounds_are_refused_naming_the_key_and_what_is_allowed(keys, message):
    with pytest.raises(config.ConfigError) as err:
        config.parse_config(scene_text(**keys))
    assert message in str(err.value)
