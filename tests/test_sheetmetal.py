"""The sheet-metal side frame: closed sheets of exact gauge, lap joints of the drawn overlap,
spots between the two sheets of their flange, the same files for the same seed.

Measured on the mesh with trimesh's ray casts (not the generator's own profile arithmetic, and
not :mod:`weldplan.geometry.flanges`, which is tested against this generator)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh

from weldplan.errors import ConfigError, InputError
from weldplan.io.joints import read_joints
from weldplan.io.mesh import load_part
from weldplan.weld.sheetmetal import (
    GAUGES_MM,
    HatProfile,
    SheetFrameSettings,
    generate_side_frame,
    main,
    read_sheets,
    station_texts,
    write_station,
)
from weldplan.weld.verify import verify_route


@pytest.fixture(scope="module")
def station():
    return generate_side_frame(rng=0)


def _hits(mesh: trimesh.Trimesh, origins: np.ndarray, d: np.ndarray) -> list[np.ndarray]:
    """Sorted distances along ``d`` of every hit of each ray from ``origins (n, 3)``."""
    locs, ray, _ = mesh.ray.intersects_location(
        origins, np.tile(d, (len(origins), 1)), multiple_hits=True
    )
    t = (locs - origins[ray]) @ d
    return [np.unique(np.round(t[ray == k], 6)) for k in range(len(origins))]


def _across(station, flange, step=0.1):
    """Points every ``step`` mm across the flange's overlap and beyond it (10 mm either
    side), 100 mm in front of the inner panel, and the ray direction (+normal)."""
    e0, e1 = (np.asarray(p) for p in flange.edge)
    r0 = np.asarray(flange.root[0])
    n = np.asarray(flange.normal)
    mid = (e0 + e1) / 2
    across = (r0 - e0) / np.linalg.norm(r0 - e0)  # from the free edge towards the root
    s = np.arange(-10.0, flange.overlap + 10.0, step)
    return mid + s[:, None] * across - 100.0 * n, s, n


def test_every_sheet_is_a_closed_thin_solid(station):
    assert len(station.sheets) == 6
    for name, m in station.sheets.items():
        assert m.is_watertight and m.is_volume, name
    for m in station.members:
        assert m.t_hat in GAUGES_MM and m.t_inner in GAUGES_MM
        assert 15.0 <= m.overlap <= 25.0


def test_thickness_and_overlap_measured_on_the_mesh_equal_the_parameters(station):
    """Rays along the stack's normal across each flange: the inner panel, the gap and the hat's
    flange have the drawn gauges and gap exactly, and both sheets are there over the overlap."""
    for f in station.flanges:
        hat, inner = (station.sheets[b] for b in f.bodies)
        P, s, n = _across(station, f)
        th_hat = _hits(hat, P, n)
        th_in = _hits(inner, P, n)
        stacked, hat_t = [], []
        for k in range(len(P)):
            if len(th_in[k]) == 2 and len(th_hat[k]) >= 2:
                a0, a1 = th_in[k]
                b0, b1 = th_hat[k][:2]
                assert a1 - a0 == pytest.approx(f.gauges[1], abs=1e-5)
                if abs(b0 - a1 - f.gap) < 1e-5:  # face to face: the stack
                    stacked.append(s[k])
                    hat_t.append(b1 - b0)
        # the hat's gauge along the normal, except by the root where the ray leaves through
        # the bend's outer face (longer, never shorter)
        assert np.median(hat_t) == pytest.approx(f.gauges[0], abs=1e-5)
        assert min(hat_t) == pytest.approx(f.gauges[0], abs=1e-5)
        width = max(stacked) - min(stacked)
        assert width == pytest.approx(f.overlap, abs=0.1 + 1e-9), f.name
        assert min(stacked) == pytest.approx(0.0, abs=0.1)  # from the free edge


def test_every_spot_lies_between_the_two_sheets_of_its_flange(station):
    flanges = {f.name: f for f in station.flanges}
    d = station.spots.directions
    for k, jid in enumerate(station.spots.ids):
        f = flanges[station.spot_flange[k]]
        p = station.spots.xyz[k]
        towards_torch = {}
        for name, m in station.sheets.items():
            for sign in (1.0, -1.0):
                t = _hits(m, p[None], sign * d[k])[0]
                if len(t):
                    towards_torch[(name, sign)] = t[0]
        near = sorted(towards_torch.items(), key=lambda kv: kv[1])[:2]
        sides = {key[1]: key[0] for key, _ in near}
        assert set(sides.values()) == set(f.bodies), jid
        assert sides[1.0] == f.bodies[1] and sides[-1.0] == f.bodies[0]  # torch side: inner
        assert [t for _, t in near] == pytest.approx([f.gap / 2] * 2, abs=1e-5)


def test_spot_pitch_is_within_the_range(station):
    for f in station.flanges:
        P = station.spots.xyz[[k for k, n in enumerate(station.spot_flange) if n == f.name]]
        gaps = np.linalg.norm(np.diff(P, axis=0), axis=1)
        assert len(P) > 10
        assert gaps.min() >= 30.0 - 1e-9 and gaps.max() <= 60.0 + 1e-9


def test_same_seed_same_files_other_seed_other_files():
    a = station_texts(generate_side_frame(rng=3))
    b = station_texts(generate_side_frame(rng=3))
    c = station_texts(generate_side_frame(rng=4))
    assert a == b
    assert a["spots.csv"] != c["spots.csv"]


def test_written_station_reads_back(tmp_path):
    assert main([str(tmp_path), "--seed", "1", "--spots", "50"]) == 0
    joints = read_joints(tmp_path / "spots.csv")
    text = (tmp_path / "spots.csv").read_text()
    assert text.startswith("# SYNTHETIC weld spots (50)") and "seed 1" in text.splitlines()[0]
    st = generate_side_frame(SheetFrameSettings(n_spots=50), rng=1)
    assert joints.ids == st.spots.ids
    np.testing.assert_allclose(joints.xyz, st.spots.xyz, atol=1e-6)
    sheets = read_sheets(tmp_path / "body.obj")
    assert list(sheets) == list(st.sheets)
    for name, m in sheets.items():
        np.testing.assert_allclose(m.vertices, st.sheets[name].vertices, atol=1e-6)
        assert m.is_watertight
    part = load_part(tmp_path / "body.obj")  # weldplan's loader: one part, a body per sheet
    assert part.body_count == 6
    assert part.area == pytest.approx(st.combined().area, rel=1e-6)


def test_bad_settings_and_files_are_one_line_errors(tmp_path):
    with pytest.raises(ConfigError, match="hold"):
        generate_side_frame(SheetFrameSettings(n_spots=10_000), rng=0)
    with pytest.raises(ConfigError, match="thickness"):
        SheetFrameSettings(thickness=(2.5, 3.0))
    with pytest.raises(ConfigError, match="crown"):
        SheetFrameSettings(pillar=HatProfile(120.0, 100.0, 40.0))
    with pytest.raises(SystemExit) as exc:
        main([str(tmp_path / "x"), "--spots", "100000"])
    assert exc.value.code == 2
    with pytest.raises(SystemExit) as exc:
        main([str(tmp_path / "y"), "--pitch", "0", "3"])
    assert exc.value.code == 2
    (tmp_path / "file").write_text("")
    with pytest.raises(SystemExit) as exc:
        main([str(tmp_path / "file" / "out")])  # a path through a file: one line, exit 2
    assert exc.value.code == 2
    bad = tmp_path / "bad.obj"
    bad.write_text("o a\nv 0 0 0\nf 1 2 3\n")
    with pytest.raises(InputError, match="line 3"):
        read_sheets(bad)


@pytest.mark.slow
def test_a_generated_frame_is_planned_whole_with_the_gun_and_the_robot(tmp_path):
    """The whole pipeline on real lap joints: every spot of a generated frame gets a verified
    gun pose, the KR 150 on the floor welds them all in one collision-free program, and the
    route re-checks at the depth the generator states (issue 29: benches and tests on these)."""
    import weldplan
    from tests.conftest import require_shared

    gun = require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    st = generate_side_frame(SheetFrameSettings(n_spots=8), rng=3)
    write_station(st, tmp_path)
    (tmp_path / "station.toml").write_text(
        f'seed = 0\n[part]\nmesh = "body.obj"\nwelds = "spots.csv"\npose = [0, 0, 600, 0, 0, 0]\n'
        f"[cell]\nspot_depth = {st.spot_depth()}\n"
        f'[[robot]]\nurdf = "{urdf}"\n[robot.tool]\nfile = "{gun}"\ntcp = "nozzle_tip"\n'
    )
    p = weldplan.plan(weldplan.load_station(tmp_path / "station.toml"))
    rr = p.robot.robot_route
    assert p.poses.poses.n_ok == 8
    assert rr.status.count("ok") == 8 and not rr.flips and rr.stats["collision_free"]
    assert p.partial() == []
    assert p.route.settings["spot_depth"] == pytest.approx(st.spot_depth())
    # one sheet deeper than the generator says: the route fails its own re-check
    shallow = dataclasses.replace(p.route, settings={**p.route.settings, "spot_depth": 0.0})
    assert not verify_route(shallow, p.cell.part).ok
