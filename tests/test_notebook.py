"""The notebooks run top to bottom, headless, so they can never rot.

``inspect_route`` plans the demo's point-tip route through ``weldplan.plan``; ``cell`` shows the
demo cell; ``station`` runs examples/demo_station.toml (the shared gun on the shared KR 150)
through ``weldplan.load_station`` and ``weldplan.plan``, saves the plan, loads it back and
re-checks it (skipped without ../shared, failed with ``WELDPLAN_REQUIRE_SHARED=1``).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.conftest import require_shared

ROOT = Path(__file__).resolve().parents[1]


def _execute(name: str, timeout: int = 300) -> list[dict]:
    """Run ``notebooks/<name>.ipynb`` in a fresh kernel from the repository root; its outputs,
    none of them an error."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    nb = nbformat.read(ROOT / "notebooks" / f"{name}.ipynb", as_version=4)
    env_path = os.environ.get("PYTHONPATH", "")
    os.environ["PYTHONPATH"] = str(ROOT) + (os.pathsep + env_path if env_path else "")
    os.environ.setdefault("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    try:
        client = nbclient.NotebookClient(
            nb, timeout=timeout, kernel_name="python3", resources={"metadata": {"path": str(ROOT)}}
        )
        client.execute()
    finally:
        if env_path:
            os.environ["PYTHONPATH"] = env_path
        else:
            os.environ.pop("PYTHONPATH", None)
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    return outputs


def _text(outputs: list[dict]) -> str:
    return "".join(o.get("text", "") for o in outputs)


@pytest.mark.parametrize("name", ["inspect_route", "cell", "station"])
def test_notebooks_are_committed_without_outputs(name):
    nbformat = pytest.importorskip("nbformat")
    nb = nbformat.read(ROOT / "notebooks" / f"{name}.ipynb", as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(not c.outputs and c.execution_count is None for c in code)


@pytest.mark.slow
def test_inspect_route_notebook_executes():
    outputs = _execute("inspect_route")
    html = [o for o in outputs if "text/html" in o.get("data", {})]
    assert any("iframe" in o["data"]["text/html"] for o in html), "no inline 3D view"
    pngs = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(pngs) >= 3, "convergence plots missing"
    assert "route ok" in _text(outputs)


@pytest.mark.slow
def test_cell_notebook_executes():
    outputs = _execute("cell")
    text = _text(outputs)
    assert "3 -> 7 free: False" in text and "1 -> 2 free: True" in text
    assert any("image/png" in o.get("data", {}) for o in outputs), "no voxel plot"


@pytest.mark.slow
def test_station_notebook_plans_saves_loads_and_verifies_the_demo_station():
    require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    text = _text(_execute("station", timeout=600))
    assert "weldplan.plan(demo_station.toml)" in text  # the summary's title
    assert "robot route" in text and "saved again, same bytes: True" in text
    assert "verdict: ok" in text
