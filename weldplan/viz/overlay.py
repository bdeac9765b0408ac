"""The weld slider laid over a static page: the tool (or the robot) at one weld at a time.

A page with a tool shows it at one weld, not a copy at every weld: an HTML range control in the
page's bottom-left corner picks the weld, and its script sets the scene accordingly through the
meshcat viewer's own commands (``viewer.handle_command``, the same ``set_transform`` a server
sends). Two kinds (:class:`WeldSlider`):

- *poses*: each weld carries the tool's ``(4, 4)`` pose in the frame of the node it moves (the
  route page: the tool's TCP frame at the weld, mm, under the route's root);
- *times*: each weld carries a time on the page's animation (the robot page: the moment the robot
  reaches the weld, s); the slider pauses the animation and seeks it there, so the robot and the
  tool stand at the weld as the timed trajectory has them.

The page's address may pick the first weld shown: ``page.html#weld=<id>`` (also for
:func:`weldplan.viz.png.render_png`, which renders a page as it opens). The live viewer has no
overlay; its *Animations* panel plays the same motion.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from html import escape

import numpy as np
from numpy.typing import ArrayLike


@dataclass(frozen=True)
class WeldSlider:
    """The data of the weld slider.

    Attributes
    ----------
    ids
        ``(w,)`` the welds in the slider's order (the route's).
    path
        The meshcat path of the node a pose moves (``/meshcat/...``), or "" for times.
    matrices
        ``(w, 16)`` the node's pose at each weld, column-major (meshcat's and three.js's order),
        mm; empty for times.
    times
        ``(w,)`` s on the page's animation; empty for poses.
    caption
        The words before the weld's id (e.g. ``"tool at weld"``).
    """

    ids: tuple[str, ...]
    path: str = ""
    matrices: tuple[tuple[float, ...], ...] = ()
    times: tuple[float, ...] = ()
    caption: str = "tool at weld"

    @classmethod
    def from_poses(
        cls, ids: list[str], poses: ArrayLike, path: str, caption: str = "tool at weld"
    ) -> WeldSlider:
        """From ``(w, 4, 4)`` poses (mm) of the node at ``path``."""
        T = np.asarray(poses, dtype=np.float64).reshape(-1, 4, 4)
        cols = tuple(tuple(float(v) for v in m.T.reshape(16)) for m in T)
        return cls(tuple(ids), path, cols, (), caption)

    @classmethod
    def from_times(cls, ids: list[str], times: ArrayLike, caption: str) -> WeldSlider:
        """From ``(w,)`` times (s) on the page's animation."""
        return cls(tuple(ids), "", (), tuple(float(t) for t in np.ravel(times)), caption)

    def html(self) -> str:
        """The control and its script, to insert before the page's ``</body>``."""
        if not self.ids:
            return ""
        data = {
            "ids": list(self.ids),
            "path": self.path,
            "matrices": [list(m) for m in self.matrices],
            "times": list(self.times),
        }
        return _SLIDER.format(
            n_max=len(self.ids) - 1,
            caption=escape(self.caption),
            data=json.dumps(data, separators=(",", ":")).replace("</", "<\\/"),
        )


_SLIDER = """<div id="weldplan-welds" style="position:fixed;left:8px;bottom:8px;z-index:10;
background:rgba(255,255,255,0.9);padding:6px 10px;border-radius:4px;font:14px sans-serif">
<div>{caption} <b id="weldplan-weld-id"></b> <span id="weldplan-weld-k"></span></div>
<input type="range" id="weldplan-weld" min="0" max="{n_max}" step="1" value="0"
 style="width:min(360px,80vw)" aria-label="{caption}">
</div>
<script>
(function () {{
  var data = {data};
  var slider = document.getElementById("weldplan-weld");
  function show(k) {{
    document.getElementById("weldplan-weld-id").textContent = data.ids[k];
    document.getElementById("weldplan-weld-k").textContent =
      "(" + (k + 1) + " of " + data.ids.length + ")";
    if (data.times.length) {{
      viewer.animator.play();
      viewer.animator.pause();
      viewer.animator.seek(data.times[k]);
      viewer.animator.display_progress(data.times[k]);
    }} else {{
      if (viewer.animator.playing) viewer.animator.pause();
      viewer.handle_command({{type: "set_transform", path: data.path, matrix: data.matrices[k]}});
    }}
    viewer.set_dirty();
  }}
  var hash = decodeURIComponent(window.location.hash.slice(1));
  if (hash.indexOf("weld=") === 0) {{
    var k0 = data.ids.indexOf(hash.slice(5));
    if (k0 >= 0) slider.value = k0;
  }}
  slider.addEventListener("input", function () {{ show(Number(slider.value)); }});
  show(Number(slider.value));
}})();
</script>"""
