"""The HTML page: header with the cube's counts, the figures as bokeh components, the points in
detail, the unstable-interval table and the scene's config, in one offline file."""
import html
from pathlib import Path

import numpy as np

from rotorsweep.pipeline import schema
from rotorsweep.pipeline.report.cubeinfo import (attractor_counts, continued_axis, has_attractor, scene_name,
                                      sweep_labels)
from rotorsweep.pipeline.report.plan import MAX_PANELS, axis_display, fixed_note, where_label
from rotorsweep.pipeline.report.stability import CLASS_MEANING, counts
from rotorsweep.pipeline.report.style import holoviews

_CSS = """<style>
table.intervals {border-collapse: collapse; font-family: sans-serif; font-size: 10pt}
table.intervals, pre.config {display: block; max-width: 100%; overflow-x: auto}  /* wide tables scroll, the page fits */
table.intervals th, table.intervals td {border: 1px solid #bbb; padding: 2px 8px; text-align: right}
table.intervals th {background: #eef2f6}
body {font-family: sans-serif; margin: 1.5em 2em; max-width: 1250px}
div.figure {margin: 1.5em 0}
pre.config {background: #f6f6f6; border: 1px solid #ddd; padding: 8px; font-size: 9pt}
table.point {border-collapse: collapse; font-family: sans-serif; font-size: 10pt}
table.point th, table.point td {border: 1px solid #ccc; padding: 2px 8px; text-align: left}
table.point th {background: #eef2f6; font-weight: normal}
</style>"""


def _items(d):
    return "".join(f"<li>{html.escape(k)}: {v}</li>" for k, v in d.items())


def _attractor_boxes(ds):
    """The attractor class counts of each sweep direction (and the hysteresis count)."""
    labels = sweep_labels(ds)
    boxes = [f"<div><b>attractor ({labels[0]})</b><ul>{_items(attractor_counts(ds))}</ul></div>"]
    if "attractor" + schema.DOWN_SUFFIX in ds:
        down = attractor_counts(ds, schema.DOWN_SUFFIX)
        if "hysteresis" in ds:
            down["hysteresis (sweeps end on different attractors)"] = int((ds["hysteresis"].values == 1).sum())
        boxes.append(f"<div><b>attractor ({labels[1]})</b><ul>{_items(down)}</ul></div>")
    return boxes


def header_html(ds, title, plan):
    """Title, scene, config hash, grid size, fixed axes, point counts and omitted panels."""
    by_status, by_class = counts(ds)
    axes = schema.point_axes(ds)
    n = int(np.prod([ds.sizes[a] for a in axes]))
    grid = " x ".join(f"{ds.sizes[a]} {axis_display(ds, a)[2]}" for a in axes)
    parts = [
        f"<h1>{html.escape(title)}</h1>",
        f"<p>scene <b>{html.escape(scene_name(ds))}</b> &middot; config hash "
        f"<code>{html.escape(str(ds.attrs.get('config_hash', 'n/a')))}</code> &middot; "
        f"{n} grid points ({html.escape(grid)})</p>",
    ]
    if plan["fixed"]:
        parts.append(f"<p>fixed: {html.escape(fixed_note(ds, plan))}</p>")
    boxes = [f"<div><b>orbit status</b><ul>{_items(by_status)}</ul></div>",
             f"<div><b>stability class</b><ul>{_items(by_class)}</ul></div>"]
    if has_attractor(ds):
        boxes += _attractor_boxes(ds)
    parts.append('<div style="display:flex;gap:4em">' + "".join(boxes) + "</div>")
    parts.append(f"<p>Stability classes: {html.escape(CLASS_MEANING)}.</p>")
    if plan["omitted"]:
        om = "; ".join(where_label(ds, c) for c in plan["omitted"])
        parts.append(f"<p><b>Panels omitted</b> (at most {MAX_PANELS} shown): {html.escape(om)}</p>")
    return "\n".join(parts)


def intervals_html(ds, header, rows):
    """The unstable-interval section: heading and table."""
    heading = f"<h2>Unstable {continued_axis(ds).replace('_', ' ')} intervals</h2>"
    if not rows:
        return heading + "<p><b>no unstable intervals</b> (every converged orbit on the grid is stable)</p>"
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "\n".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in rows)
    return heading + f'<table class="intervals"><thead><tr>{head}</tr></thead>\n<tbody>\n{body}\n</tbody></table>'


def bistable_html(ds, header, rows):
    """The bistable-interval section (only where the sweep found jumps): heading and table."""
    if not rows:
        return ""
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "\n".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in rows)
    return (f"<h2>Bistable {continued_axis(ds).replace('_', ' ')} intervals: the two stable orbits that coexist</h2>"
            f'<table class="intervals"><thead><tr>{head}</tr></thead>\n<tbody>\n{body}\n</tbody></table>')


def point_table_html(rows):
    body = "\n".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>" for k, v in rows)
    return f'<table class="point">\n{body}\n</table>'


def save_html(path, title, header, figs, intervals, config_toml, points=()):
    """A plain HTML page: the header, tables and config as HTML, the figures ((caption, figure)
    pairs, then the points' (title, figure, table HTML)) as bokeh components, with bokeh's
    JavaScript inlined (no network). Panel's own save() would link its theme CSS from a CDN
    even with inline resources."""
    from bokeh.core.validation import silence
    from bokeh.core.validation.warnings import FIXED_SIZING_MODE
    from bokeh.embed import components
    from bokeh.embed.bundle import bundle_for_objs_and_resources
    from bokeh.resources import INLINE

    # the multiplier panels are sized by their frame (square, for round unit circles), which
    # bokeh's check of fixed sizing does not know
    silence(FIXED_SIZING_MODE, True)
    hv = holoviews()
    models = [hv.render(fig, backend="bokeh") for _, fig in figs]
    models += [hv.render(fig, backend="bokeh") for _, fig, _ in points]
    # a page without figures (the modes of a model with no shaft speed and no stations): no bokeh
    script, divs, resources = "", (), ""
    if models:
        script, divs = components(models)
        # only the JavaScript these models need (bokeh's INLINE.render() would add every registered
        # extension, Panel's included, some of which load relative URLs)
        bundle = bundle_for_objs_and_resources(models, INLINE)
        resources = bundle.scripts() + "".join(f"<style>{css}</style>" for css in bundle.css_raw)
    body = [header]
    for (caption, _), div in zip(figs, divs):
        body.append(f'<h2>{html.escape(caption)}</h2>\n<div class="figure">{div}</div>')
    if points:
        body.append("<h2>Points in detail</h2>")
    for (name, _, rows_html), div in zip(points, divs[len(figs):]):
        body.append(f'<h3>{html.escape(name)}</h3>\n<div class="figure">{div}</div>\n{rows_html}')
    body.append(intervals)
    body.append('<h2>Configuration</h2><pre class="config">'
                + html.escape(config_toml or "(no config_toml in the cube)") + "</pre>")
    page = ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{html.escape(title)}</title>\n{resources}\n{_CSS}\n</head>\n"
            "<body>\n" + "\n".join(body) + f"\n{script}\n</body>\n</html>\n")
    Path(path).write_text(page, encoding="utf-8")


def columns_html(title, cols, digits=10):
    """<h2>title</h2> and a table of columns {name: values} (floats to `digits` significant digits)."""
    def cell(v):
        return f"{v:.{digits}g}" if isinstance(v, float) else str(v)
    head = "".join(f"<th>{html.escape(k)}</th>" for k in cols)
    rows = "\n".join("<tr>" + "".join(f"<td>{html.escape(cell(v))}</td>" for v in vals) + "</tr>"
                     for vals in zip(*cols.values()))
    return f'<h2>{html.escape(title)}</h2><table class="intervals"><thead><tr>{head}</tr></thead>\n<tbody>{rows}</tbody></table>'


def write_result_report(out_dir, title, header, figures, tables, config_toml, csv_name, csv_text):
    """A result's report (continuation, backbone): one PNG per figure (matplotlib), report.html
    (bokeh figures, header, tables, config) and a CSV; figures(backend) -> [(caption, file, fig)].
    Returns the paths as rotorsweep.pipeline.report.make_report does."""
    from rotorsweep.pipeline.report import style

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = out / csv_name
    csv_path.write_text(csv_text + "\n")
    pngs = []
    with style.backend("matplotlib") as hv:
        for _, filename, fig in figures("matplotlib"):
            hv.save(fig, out / filename, backend="matplotlib", dpi=style.DPI)
            pngs.append(out / filename)
    html_path = out / "report.html"
    with style.backend("bokeh"):
        figs = [(caption, fig) for caption, _, fig in figures("bokeh")]
        save_html(html_path, title, header, figs, tables, config_toml)
    return {"html": html_path, "png": pngs, "csv": csv_path, "points": []}
