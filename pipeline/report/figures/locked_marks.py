"""A torus branch's locked p/q markers in the continuation report's amplitude panels.

The event row of a locked ratio (rotorsweep.pipeline.torus_events) carries the amplitudes of ONE
periodic orbit: the linked orbit at support-forcing phase theta = 0. The torus's amplitude at that
ratio is taken over all phases theta of its circle (the whole family of locked orbits), so the
linked orbit's lies at or below it. The marker is drawn on the torus curve -- its value at the
event parameter, linear between the branch's two points around the event, which is what the
drawn curve shows there -- and the linked orbit's own value is in its hover."""
import numpy as np

from rotorsweep.pipeline.report import style
from rotorsweep.kernels.continuation import events as ev

LINKED_LABEL = "linked orbit at θ = 0"
HOVER_COLOUR = "#C00000"


def locked(ds):
    """Per event: whether it is a torus branch's locked ratio."""
    return ds["event_type"].values == ev.LOCKED


def curve_value(x, y, index, at):
    """The branch's value at parameter `at` on its segment from point `index` to index + 1 (where
    the event was detected), linear in the parameter as the drawn curve is; the point's own value
    at the branch's end or on a segment of zero length."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if index + 1 >= x.size or not np.isfinite(x[index + 1]) or x[index + 1] == x[index]:
        return float(y[index])
    t = (at - x[index]) / (x[index + 1] - x[index])
    return float(y[index] + t * (y[index + 1] - y[index]))


def on_curve(ds, xs, ys, event_xs, event_ys):
    """The events' y with each locked event moved onto its branch's curve (curve_value); the
    other events keep theirs (a located event of a periodic branch is a point of its curve)."""
    out = np.array(event_ys, float)
    branch, index = ds["event_branch"].values, ds["event_point"].values
    for k in np.flatnonzero(locked(ds)):
        out[k] = curve_value(xs[branch[k]], ys[branch[k]], int(index[k]), event_xs[k])
    return out


def hover_marks(hv, ds, mine, event_xs, marker_ys, orbit_ys, dims, labels, backend):
    """bokeh: the locked markers of one branch with a hover that reads the parameter, the
    torus's value (the marker's y) and the linked orbit's own value (one element; none where the
    branch has no locked event, or for matplotlib)."""
    sel = mine & locked(ds)
    if backend != "bokeh" or not sel.any():
        return []
    notes = [str(n).split(";")[0] for n in ds["event_note"].values[sel]]    # "p/q: torus stable"
    marks = hv.Points((event_xs[sel], marker_ys[sel], orbit_ys[sel], notes), list(dims), ["linked_orbit", "ratio"])
    tooltips = [(labels[0], f"@{{{dims[0].name}}}"), (f"torus: {labels[1]}", f"@{{{dims[1].name}}}"),
                (f"{LINKED_LABEL}: {labels[1]}", "@{linked_orbit}"), ("locked", "@{ratio}")]
    return [marks.opts(**style.marker_style(backend, HOVER_COLOUR, 9, "D"), tools=["hover"],
                       hover_tooltips=tooltips, backend=backend)]
