"""The tool model: loaders (URDF, mesh + TCP), the built-in torch, the contact-zone cut."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import trimesh

from tests.conftest import require_shared
from weldplan.errors import InputError
from weldplan.tool import arc_torch, load_tool_urdf, shared_spot_gun, tool_from_mesh
from weldplan.tool.model import ZONE_EDGE_MM

GUN = ("tools", "spot_welding_gun")


def _ry(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def test_shared_gun_has_the_documented_tcp():
    d = require_shared(*GUN)
    gun = shared_spot_gun(d)
    raw = trimesh.load(d / "spot_welding_gun.stl", force="mesh", process=False)
    # README: TCP = nozzle_tip joint, xyz (0.67936, 0, 0.00043) m, rpy (0, 1.5708, 0) from root
    t = np.array([679.36, 0.0, 0.43])
    R = _ry(1.5708)
    expected = (np.asarray(raw.vertices) * 1000.0 - t) @ R
    np.testing.assert_allclose(gun.vertices, expected, atol=1e-6)
    # the TCP sits at the moving electrode's tip (README: 1 mm from it), +z towards the fixed one
    assert 0.9 < np.linalg.norm(gun.vertices, axis=1).min() < 1.1
    ahead, _, _ = gun.mesh.ray.intersects_location([[0, 0, 2.0]], [[0, 0, 1.0]])
    assert 40 < ahead[:, 2].min() < 55  # the fixed electrode's face, across the gun's opening


def test_mesh_plus_explicit_tcp_equals_the_urdf(tmp_path):
    d = require_shared(*GUN)
    a = shared_spot_gun(d)
    b = tool_from_mesh(d / "spot_welding_gun.stl", "0.67936,0,0.00043,0,90,0", units="m")
    np.testing.assert_allclose(a.vertices, b.vertices, atol=0.01)  # 1.5708 rad vs 90 deg


def test_urdf_own_mesh_reference_applies_origin_and_scale(tmp_path):
    box = trimesh.creation.box((0.2, 0.1, 0.1))  # metres after scale 0.5: 100 x 50 x 50 mm
    box.apply_scale(2.0)
    box.export(tmp_path / "body.stl")
    (tmp_path / "t.urdf").write_text(
        """<robot name="t">
  <link name="base"><collision><origin xyz="0.1 0 0" rpy="0 0 0"/>
    <geometry><mesh filename="body.stl" scale="0.25 0.25 0.25"/></geometry></collision></link>
  <link name="tip"/>
  <joint name="tcp" type="fixed"><origin xyz="0.15 0 0" rpy="0 0 0"/>
    <parent link="base"/><child link="tip"/></joint>
</robot>"""
    )
    tool = load_tool_urdf(tmp_path / "t.urdf")
    lo, hi = tool.vertices.min(axis=0), tool.vertices.max(axis=0)
    # box 100 x 50 x 50 mm centred at x = 100 mm; TCP at x = 150 mm, same axes
    np.testing.assert_allclose(lo, [-100.0, -25.0, -25.0], atol=1e-4)  # STL stores float32
    np.testing.assert_allclose(hi, [0.0, 25.0, 25.0], atol=1e-4)  # STL stores float32


def _one_line(exc: pytest.ExceptionInfo, *words: str) -> None:
    msg = str(exc.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_urdf_without_tcp_is_a_one_line_error(tmp_path):
    d = require_shared(*GUN)
    with pytest.raises(InputError) as exc:
        load_tool_urdf(
            d / "spot_welding_gun.urdf", tcp="torch_tip", mesh=d / "spot_welding_gun.stl"
        )
    _one_line(exc, "spot_welding_gun.urdf", "field 'tcp'", "torch_tip")
    (tmp_path / "no_joint.urdf").write_text('<robot name="x"><link name="root"/></robot>')
    with pytest.raises(InputError) as exc:
        load_tool_urdf(tmp_path / "no_joint.urdf", mesh=d / "spot_welding_gun.stl")
    _one_line(exc, "no_joint.urdf", "no fixed joint")


def test_mesh_in_other_units_is_a_one_line_error(tmp_path):
    d = require_shared(*GUN)
    with pytest.raises(InputError) as exc:  # metres read as millimetres: 0.83 mm long
        tool_from_mesh(d / "spot_welding_gun.stl", "0.67936,0,0.00043,0,90,0", units="mm")
    _one_line(exc, "spot_welding_gun.stl", "field 'units'", "wrong unit")
    raw = trimesh.load(d / "spot_welding_gun.stl", force="mesh")
    raw.apply_scale(1000.0)
    raw.export(tmp_path / "gun_mm.stl")
    with pytest.raises(InputError) as exc:  # millimetres declared metres: 830 m long
        load_tool_urdf(d / "spot_welding_gun.urdf", mesh=tmp_path / "gun_mm.stl", mesh_units="m")
    _one_line(exc, "gun_mm.stl", "field 'units'")
    # the same file with the right unit loads and equals the gun
    ok = load_tool_urdf(d / "spot_welding_gun.urdf", mesh=tmp_path / "gun_mm.stl", mesh_units="mm")
    np.testing.assert_allclose(ok.extent, shared_spot_gun(d).extent, atol=1e-3)


def test_tcp_outside_the_tool_is_a_one_line_error(tmp_path):
    d = require_shared(*GUN)
    with pytest.raises(InputError) as exc:
        tool_from_mesh(d / "spot_welding_gun.stl", "1.5,0,0,0,90,0", units="m")
    _one_line(exc, "spot_welding_gun.stl", "field 'tcp'", "outside the tool")
    with pytest.raises(InputError) as exc:
        tool_from_mesh(d / "spot_welding_gun.stl", "0.6,0,0,0,90", units="m")
    _one_line(exc, "field 'tcp'", "six")
    bad = tmp_path / "far.urdf"
    bad.write_text(
        (d / "spot_welding_gun.urdf").read_text().replace('xyz="0.67936 0 0.00043"', 'xyz="2 0 0"')
    )
    with pytest.raises(InputError) as exc:
        load_tool_urdf(bad, mesh=d / "spot_welding_gun.stl")
    _one_line(exc, "far.urdf", "joint 'nozzle_tip' origin")


def test_arc_torch_mesh_with_its_wire_stickout_loads_and_a_far_tcp_is_refused(tmp_path):
    """arc_torch()'s TCP is the wire tip, 15 mm beyond the nozzle's mouth and so 15 mm outside
    its mesh's bounding box: the torch exported as a mesh loads with its own TCP (the CLI
    refused it at a 5 mm margin, so the bench's torch could not be given as --tool torch.stl);
    a TCP a tool length away is still an error."""
    t = arc_torch(bend_angle=0.0)
    assert t.vertices[:, 2].max() == pytest.approx(-15.0)  # the nozzle's mouth
    t.mesh.export(tmp_path / "torch.stl")
    got = tool_from_mesh(tmp_path / "torch.stl", "0,0,0,0,0,0")
    np.testing.assert_allclose(got.extent, t.extent, atol=1e-3)
    np.testing.assert_allclose(got.vertices.max(axis=0)[2], -15.0, atol=1e-3)
    with pytest.raises(InputError) as exc:
        tool_from_mesh(tmp_path / "torch.stl", "0,0,41,0,0,0")  # 56 mm beyond the mouth
    _one_line(exc, "torch.stl", "field 'tcp'", "outside the tool")


@pytest.mark.parametrize("cone", [None, 15.0])
def test_outside_zone_covers_the_tool_outside_the_zone_and_little_inside(cone):
    tool = dataclasses.replace(arc_torch(), tip_cone=cone, _cache={})
    r = 30.0
    v, f = tool.outside_zone(r)
    kept = trimesh.Trimesh(v, f, process=False)
    # a kept triangle with a corner in the zone is finer than ZONE_EDGE_MM: it reaches at most
    # that far into the zone
    tri = v[f]
    touches = tool.in_zone(tri, r).any(axis=1)
    assert not tool.in_zone(tri, r).all(axis=1).any()
    edges = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
    assert touches.any() and edges[touches].max() <= ZONE_EDGE_MM
    # every sampled point of the tool outside the zone lies on what is kept
    pts, _ = trimesh.sample.sample_surface(tool.mesh, 4000, seed=0)
    pts = pts[~tool.in_zone(pts, r)]
    _, dist, _ = trimesh.proximity.closest_point(kept, pts)
    assert dist.max() < 1e-6
    nearest = np.linalg.norm(v, axis=1).min()
    if cone is None:  # the nozzle mouth (15 mm from the TCP) is gone with the sphere
        assert nearest >= r - ZONE_EDGE_MM - 1e-9
    else:  # only the tip cone is exempt: the nozzle's rim (40 deg off the axis) is kept
        assert nearest < 20.0


def test_arc_torch_straight_and_bent():
    straight = arc_torch(bend_angle=0.0, diameter=20.0, body_diameter=40.0)
    assert np.hypot(straight.vertices[:, 0], straight.vertices[:, 1]).max() <= 20.0 + 1e-9
    assert straight.vertices[:, 2].max() <= 1e-9  # all behind the TCP (+z points into the part)
    bent = arc_torch(bend_angle=30.0, neck_length=100.0, body_length=50.0)
    far = bent.vertices[np.argmin(bent.vertices[:, 2])]
    assert far[0] < -(100.0 + 50.0) * math.sin(math.radians(30.0)) + 30.0  # swung towards -x
    with pytest.raises(ValueError):
        arc_torch(diameter=0.0)
