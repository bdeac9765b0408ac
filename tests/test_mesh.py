"""Loading parts: formats, merged bodies, units and scale, degenerate faces, unreadable files."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from conftest import require_shared

from weldplan.errors import InputError
from weldplan.io.mesh import load_part


def two_boxes() -> trimesh.Scene:
    a = trimesh.creation.box(extents=(10, 20, 30))
    b = trimesh.creation.box(extents=(4, 4, 4))
    scene = trimesh.Scene()
    scene.add_geometry(a, node_name="a")
    scene.add_geometry(
        b, node_name="b", transform=trimesh.transformations.translation_matrix([100, 0, 0])
    )
    return scene


@pytest.mark.parametrize("suffix", ["stl", "obj", "ply", "off", "glb"])
def test_single_body_formats_load_in_mm(tmp_path, suffix):
    box = trimesh.creation.box(extents=(10, 20, 30))
    path = tmp_path / f"box.{suffix}"
    box.export(str(path))
    mesh = load_part(path)
    assert len(mesh.faces) == 12
    np.testing.assert_allclose(mesh.extents, [10, 20, 30], atol=1e-5)


@pytest.mark.parametrize("suffix", ["glb", "gltf", "obj"])
def test_multi_body_files_are_merged_with_their_transforms(tmp_path, suffix):
    path = tmp_path / f"parts.{suffix}"
    exported = two_boxes().export(file_type=suffix)
    if isinstance(exported, dict):  # gltf writes buffers beside the json
        for name, data in exported.items():
            (tmp_path / (path.name if name.endswith(".gltf") else name)).write_bytes(data)
    else:
        path.write_bytes(exported if isinstance(exported, bytes) else exported.encode())
    mesh = load_part(path)
    assert len(mesh.faces) == 24
    np.testing.assert_allclose(mesh.bounds, [[-5, -10, -15], [102, 10, 15]], atol=1e-5)


def test_units_scale_and_length(tmp_path):
    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=(1, 2, 4)).export(str(path))
    np.testing.assert_allclose(load_part(path, units="m").extents, [1000, 2000, 4000])
    np.testing.assert_allclose(load_part(path, units="cm", scale=2).extents, [20, 40, 80])
    np.testing.assert_allclose(load_part(path, length=4500).extents, [1125, 2250, 4500])
    with pytest.raises(InputError, match="scale or length"):
        load_part(path, scale=2, length=10)
    with pytest.raises(InputError, match="positive"):
        load_part(path, scale=-1)
    with pytest.raises(InputError, match="unknown units"):
        load_part(path, units="parsec")


def test_degenerate_faces_are_removed(tmp_path):
    path = tmp_path / "tri.obj"
    path.write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 5 5 5\n"
        "f 1 2 3\n"  # a real triangle
        "f 1 2 4\n"  # collinear: zero area
        "f 1 1 3\n"  # repeated vertex
    )
    mesh = load_part(path)
    assert len(mesh.faces) == 1
    assert len(mesh.vertices) == 3  # the unreferenced vertices are gone too
    assert mesh.area == pytest.approx(0.5)


@pytest.mark.parametrize(
    ("name", "content", "words"),
    [
        ("empty.stl", b"", "cannot read mesh|no non-degenerate"),
        ("empty.obj", b"# nothing here\n", "no triangle mesh|no non-degenerate|cannot read"),
        ("garbage.ply", b"this is not a ply file\x00\x01", "cannot read mesh"),
        ("flat.obj", b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "no non-degenerate"),
        ("part.step", b"ISO-10303-21;", "unsupported mesh format"),
    ],
)
def test_empty_or_unreadable_meshes_are_input_errors_naming_the_file(
    tmp_path, name, content, words
):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(InputError, match=words) as info:
        load_part(path)
    assert info.value.path == str(path)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="not found") as info:
        load_part(tmp_path / "absent.stl")
    assert "absent.stl" in str(info.value)


def test_car2_scales_to_a_4500_mm_body():
    path = require_shared("bodies", "car2.obj")
    mesh = load_part(path, length=4500)
    assert mesh.extents.max() == pytest.approx(4500)
    assert len(mesh.faces) == 18394
    # about 99 units long in the file (data README): the factor is about 45.4
    raw = trimesh.load(str(path), force="mesh")
    assert 4500 / raw.extents.max() == pytest.approx(45.4, abs=0.1)
