"""Checks of a report's bokeh figures shared by the result kinds' tests (no browser)."""
WINDOW = 1400     # px: every figure fits a window this wide


def plots_of(figures):
    """(caption, bokeh Plot) of every panel of [(caption, filename, HoloViews figure)]."""
    from bokeh.models import Plot
    from rotorsweep.pipeline.report import style
    hv = style.holoviews()
    with style.backend("bokeh"):
        return [(caption, plot) for caption, _, fig in figures
                for plot in hv.render(fig, backend="bokeh").select({"type": Plot})]


def assert_legend_hover_and_width(figures):
    """A legend with entries and a hover tool on every plot, none wider than the window."""
    from bokeh.models import HoverTool, Legend
    for caption, plot in plots_of(figures):
        assert [i for legend in plot.select({"type": Legend}) for i in legend.items], caption
        assert plot.select({"type": HoverTool}), caption
        assert (plot.width or plot.frame_width) <= WINDOW, caption
