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


CUBE_OBJ = (
    "v 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nv 0 0 10\nv 10 0 10\nv 10 10 10\nv 0 10 10\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
    "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n"
)


@pytest.mark.parametrize("bad", ["nan", "inf", "-inf"])
def test_non_finite_vertex_is_an_input_error_naming_the_vertex(tmp_path, bad):
    """trimesh's processing drops the faces of a NaN vertex without a word (a hole a route
    could cross): weldplan refuses the file instead."""
    path = tmp_path / "cube.obj"
    path.write_text(CUBE_OBJ.replace("v 10 10 10", f"v 10 {bad} 10"))
    with pytest.raises(InputError, match=r"1 of 8 vertices have a NaN or infinite") as info:
        load_part(path)
    assert info.value.path == str(path)
    assert "vertex 6" in str(info.value)  # 0-based index of the 7th vertex
    assert "faces" in str(info.value)


@pytest.mark.parametrize(
    ("text", "kw"),
    [
        (CUBE_OBJ.replace("v 10 10 10", "v 10 1e300 10"), {}),
        (CUBE_OBJ, {"scale": 1e300}),
        (CUBE_OBJ, {"units": "m", "scale": 1e6}),
    ],
)
def test_absurd_coordinates_are_input_errors(tmp_path, text, kw):
    path = tmp_path / "cube.obj"
    path.write_text(text)
    with pytest.raises(InputError, match="beyond the") as info:
        load_part(path, **kw)
    assert info.value.path == str(path)


def test_removed_faces_are_reported_in_the_log_and_the_metadata(tmp_path, caplog):
    path = tmp_path / "cube.obj"
    # one zero-area face and one face repeated (in another vertex order)
    path.write_text(CUBE_OBJ + "f 1 2 1\nf 3 2 1\n")
    with caplog.at_level("WARNING", logger="weldplan.io.mesh"):
        mesh = load_part(path)
    assert len(mesh.faces) == 12
    meta = mesh.metadata["weldplan"]
    assert meta["repairs"] == {"degenerate_faces": 1, "duplicate_faces": 1}
    assert "removed 1 degenerate (zero-area) and 1 duplicate faces" in caplog.text
    clean = tmp_path / "clean.obj"
    clean.write_text(CUBE_OBJ)
    assert load_part(clean).metadata["weldplan"]["repairs"] == {
        "degenerate_faces": 0,
        "duplicate_faces": 0,
    }


def test_bad_option_types_are_input_errors(tmp_path):
    path = tmp_path / "cube.obj"
    path.write_text(CUBE_OBJ)
    for kw in ({"scale": "big"}, {"scale": float("nan")}, {"length": 0}, {"units": None}):
        with pytest.raises(InputError):
            load_part(path, **kw)


def test_provenance_metadata_and_geometry_hash(tmp_path):
    from weldplan.io.mesh import file_sha256, geometry_hash

    path = tmp_path / "cube.obj"
    path.write_text(CUBE_OBJ)
    a, b = load_part(path), load_part(path)
    c = load_part(path, scale=2.0)
    assert a.metadata["weldplan"]["file_sha256"] == file_sha256(path)
    assert a.metadata["weldplan"]["units"] == "mm"
    assert c.metadata["weldplan"]["scale"] == 2.0
    assert load_part(path, units="m").metadata["weldplan"]["scale"] == 1000.0
    assert geometry_hash(a) == geometry_hash(b)
    assert geometry_hash(a) != geometry_hash(c)
