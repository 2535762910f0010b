"""The report's figures, each registered by its own module (rotorsweep.pipeline.report.figures), and the
question which of them a cube's report shows.

    register(Figure(name="lle", filename="lle.png", title="Largest Lyapunov exponent vs {axis}",
                    applies=has_attractor, build=lambda ds, backend, intervals: fig_lle(ds, backend)))

Figures appear in the report in registration order, which pipeline/report/figures/__init__.py
fixes by importing the figure modules in order.
"""
from dataclasses import dataclass
from typing import Callable

from rotorsweep.pipeline.report.cubeinfo import continued_axis
from rotorsweep.pipeline.report.plan import axis_display


def _always(ds):
    return True


@dataclass(frozen=True)
class Figure:
    """One figure of the report.

    name: registry key; filename: its PNG in the report directory; title: its HTML caption,
    with {axis} standing for the continued axis's label (e.g. "shaft speed");
    applies(ds): whether the cube holds what the figure needs;
    build(ds, backend, intervals): the HoloViews object styled for backend "bokeh" or
    "matplotlib" (intervals: query.unstable_intervals of the cube, computed once per report)."""
    name: str
    filename: str
    title: str
    build: Callable
    applies: Callable = _always

    def caption(self, ds):
        return self.title.format(axis=axis_display(ds, continued_axis(ds))[2])


_FIGURES = {}


def register(figure):
    """Add a figure to the report (after those registered before it)."""
    if figure.name in _FIGURES:
        raise ValueError(f"report figure {figure.name!r} is registered twice")
    _FIGURES[figure.name] = figure
    return figure


def figures_for(ds):
    """The registered figures that apply to the cube, in report order."""
    return [f for f in _FIGURES.values() if f.applies(ds)]


def figure_named(name):
    """The registered figure called `name`."""
    try:
        return _FIGURES[name]
    except KeyError:
        raise ValueError(f"no report figure {name!r}; registered: {', '.join(_FIGURES)}") from None
