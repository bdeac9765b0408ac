"""The allocate-plan rounds in the station JSON (weldplan.multi.saved): written, read back,
re-checked by ``weldplan verify`` (weldplan.multi.recheck.rounds_check) and printed by
``weldplan view``; a station JSON written before they were recorded still reads. Fast: a
station JSON built from an allocation report of a small synthetic station, no planning."""

from __future__ import annotations

import json

import numpy as np
import pytest


def _station_json(tmp_path, rounds=None):
    """A station JSON of two robots (their shares from an allocation report of six welds),
    each robot's recorded timed cycle the kept round's, with ``rounds`` (``None``: the entry
    left out, as in an older file)."""
    from weldplan.multi import ReachMap, allocation_report
    from weldplan.multi.saved import FORMAT_VERSION, STATION_FORMAT

    g = np.random.default_rng(0)
    rep = allocation_report(ReachMap.of(np.ones((2, 6), bool)), np.full((2, 6), 0.5),
                            g.uniform(0.2, 1.0, (2, 6, 6)), rng=0)  # fmt: skip
    timed = (4.25, 3.5)
    d = {
        "format": STATION_FORMAT, "version": FORMAT_VERSION, "station_file": None, "seed": 0,
        "robots": [{"name": n, "welds": list(rep.ours.welds_of(k)), "timed_cycle": timed[k]}
                   for k, n in enumerate(rep.ours.robots)],
        "allocation": rep.to_dict(), "schedule": None, "cycle_time": max(timed),
        "interference": "not checked", "replay": None,
    }  # fmt: skip
    if rounds is not None:
        d["rounds"] = rounds
    path = tmp_path / "route_station.json"
    path.write_text(json.dumps(d))
    return path


ROUNDS = [
    {"model_cycle": 3.1, "timed_cycle": 4.75, "timed": [4.75, 3.5], "planned": [0, 1]},
    {"model_cycle": 3.6, "timed_cycle": 4.25, "timed": [4.25, 3.5], "planned": [0]},
    {"model_cycle": 3.7, "timed_cycle": 4.25, "timed": [4.25, 3.75], "planned": [1]},
]


def test_the_rounds_read_back_and_verify_finds_the_kept_one_is_the_programs(tmp_path):
    from weldplan.multi.calibrate import CalibrationRound
    from weldplan.multi.recheck import rounds_check
    from weldplan.multi.saved import load_station_plan

    saved = load_station_plan(_station_json(tmp_path, ROUNDS))
    assert saved.rounds == tuple(
        CalibrationRound(r["model_cycle"], r["timed_cycle"], tuple(r["timed"]),
                         tuple(r["planned"])) for r in ROUNDS
    )  # fmt: skip
    assert [c.to_dict() for c in saved.rounds] == ROUNDS
    assert saved.kept_round == 1  # the least timed cycle, the first of equals
    lines = saved.rounds_lines()
    assert lines[1] == "round 2: allocation 3.60 s, timed 4.25 s, re-planned r0 (kept)"
    assert lines[0].endswith("re-planned r0, r1") and "(kept)" not in lines[2]
    check = rounds_check(saved)
    assert check.ok and "3 allocate-plan round(s); round 2 kept" in check.text
    # a round that re-planned nothing at the kept cycle (the same plans, a newer allocation)
    # is the one kept, as weldplan.multi.calibrate.allocate_and_plan keeps it
    same = [*ROUNDS[:2], {**ROUNDS[1], "model_cycle": 3.65, "planned": []}]
    again = load_station_plan(_station_json(tmp_path, same))
    assert again.kept_round == 2 and rounds_check(again).ok


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda r: r[1].update(timed=[4.0, 3.5], timed_cycle=4.0), "r0: round 2 timed it 4.000"),
        (lambda r: r[0].update(timed_cycle=5.0), "round 1: timed cycle 5.000000 s is not"),
        (lambda r: r[2].update(planned=[2]), "round 3 is not over the station's 2 robots"),
        (lambda r: r[0].update(timed=[4.75]), "round 1 is not over"),
    ],
)
def test_verify_fails_rounds_that_disagree_with_the_programs(tmp_path, edit, words):
    from weldplan.multi.recheck import rounds_check
    from weldplan.multi.saved import load_station_plan

    rounds = json.loads(json.dumps(ROUNDS))
    edit(rounds)
    check = rounds_check(load_station_plan(_station_json(tmp_path, rounds)))
    assert not check.ok and words in check.text


def test_a_station_json_without_rounds_still_reads_and_a_bad_one_is_named(tmp_path):
    from weldplan.errors import InputError
    from weldplan.multi.recheck import rounds_check
    from weldplan.multi.saved import load_station_plan

    old = load_station_plan(_station_json(tmp_path))
    assert old.rounds == () and old.kept_round is None and old.rounds_lines() == []
    assert rounds_check(old) is None  # nothing recorded, nothing to re-check
    with pytest.raises(InputError, match="not a valid entry") as e:
        load_station_plan(_station_json(tmp_path, [{"model_cycle": 1.0}]))
    assert e.value.field == "rounds"
