"""viz: views of results (meshcat routes, matplotlib plots); algorithms never import it.

:func:`show` is the notebook view of a route::

    import weldplan.viz
    weldplan.viz.show(route, cell)
"""

from __future__ import annotations

from typing import Any

__all__ = ["render_png", "show"]


def render_png(page: str, path: Any, settings: Any = None) -> Any:
    """Render a static page (:func:`weldplan.viz.viewer.static_html`,
    :func:`weldplan.viz.robot_scene.robot_html`) to a PNG at ``path`` by headless Chromium,
    written whole or not at all; returns the path (:func:`weldplan.viz.png.render_png`)."""
    from weldplan.viz.png import render_png as _render

    return _render(page, path, settings)


def show(route: Any, part: Any = None, *, height: int = 480) -> Any:
    """An inline, self-contained 3D view of ``route`` for Jupyter.

    Parameters
    ----------
    route
        A :class:`weldplan.weld.route.Route`.
    part
        The part mesh, a cell or a collision model (drawn beside the route); None draws the
        route alone.
    height
        Height of the view in pixels.

    Returns
    -------
    IPython.display.HTML
        The static meshcat page (:func:`weldplan.viz.viewer.static_html`) in an iframe.
    """
    from weldplan.viz.viewer import jupyter_view  # meshcat and trimesh load only when used

    return jupyter_view(route, part, height=height)
