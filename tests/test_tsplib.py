"""TSPLIB reader: the optimal tours reproduce the known optima; rounding rules; explicit
matrices; errors that name the file, line and field; the sequencer on a real instance."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import require_shared

from weldplan.errors import InputError
from weldplan.io.tsplib import (
    distance_matrix,
    read_best_solutions,
    read_tour,
    read_tsplib,
    tour_length,
)
from weldplan.optim.discrete.sequence import solve_sequence

WITH_TOURS = ("eil51", "berlin52", "st70", "att48", "kroA100", "ch130", "a280")


@pytest.mark.parametrize("name", WITH_TOURS)
def test_optimal_tours_reproduce_known_optima(name):
    folder = require_shared("tsplib")
    best = read_best_solutions(folder / "bestSolutions.txt")
    prob = read_tsplib(folder / f"{name}.tsp")
    D = prob.matrix()
    tour = read_tour(folder / f"{name}.opt.tour")
    assert prob.dimension == len(tour) == D.shape[0]
    assert tour_length(D, tour) == best[name]
    assert np.array_equal(D, D.T)


def test_lin318_reads():
    folder = require_shared("tsplib", "lin318.tsp")
    prob = read_tsplib(folder)
    assert prob.dimension == 318 and prob.edge_weight_type == "EUC_2D"
    assert prob.coords.shape == (318, 2)


def test_sequencer_on_eil51_polish_within_two_percent():
    folder = require_shared("tsplib")
    D = read_tsplib(folder / "eil51.tsp").matrix()
    s = solve_sequence(D, method="nn", closed=True, rng=0)
    assert s.cost <= 1.02 * 426
    assert s.start_cost > s.cost


def test_rounding_rules():
    X = np.array([[0.0, 0.0], [3.0, 4.0], [1.0, 1.0]])
    assert distance_matrix(X, "EUC_2D")[0, 1] == 5
    assert distance_matrix(X, "EUC_2D")[0, 2] == 1  # nint(1.414)
    assert distance_matrix(X, "CEIL_2D")[0, 2] == 2
    assert distance_matrix(X, "MAN_2D")[0, 2] == 2
    assert distance_matrix(X, "MAX_2D")[0, 1] == 4
    # ATT: r = sqrt(25 / 10) = 1.58, nint 2 >= r -> 2; sqrt(2 / 10) = 0.447 -> nint 0 < r -> 1
    assert distance_matrix(X, "ATT")[0, 1] == 2
    assert distance_matrix(X, "ATT")[0, 2] == 1


def test_geo_distance():
    # Two points on the equator one degree apart: RRR * (pi' / 180) = 111.3 km -> int(. + 1)
    X = np.array([[0.0, 0.0], [0.0, 1.0], [0.30, 0.0]])  # 0.30 = 0 deg 30 min
    D = distance_matrix(X, "GEO")
    assert D[0, 1] == int(6378.388 * 3.141592 / 180 + 1.0)
    assert D[0, 2] == int(6378.388 * 3.141592 * 0.5 / 180 + 1.0)
    assert np.array_equal(D, D.T)


EXPLICIT = {
    "FULL_MATRIX": "0 1 2\n1 0 3\n2 3 0",
    "UPPER_ROW": "1 2\n3",
    "LOWER_ROW": "1\n2 3",
    "UPPER_DIAG_ROW": "0 1 2 0 3 0",
    "LOWER_DIAG_ROW": "0\n1 0\n2 3 0",
    "UPPER_COL": "1\n2 3",
    "LOWER_DIAG_COL": "0 1 2 0 3 0",
}


@pytest.mark.parametrize("fmt", sorted(EXPLICIT))
def test_explicit_formats(tmp_path: Path, fmt):
    text = (
        "NAME: tiny\nTYPE: TSP\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EXPLICIT\n"
        f"EDGE_WEIGHT_FORMAT: {fmt}\nEDGE_WEIGHT_SECTION\n{EXPLICIT[fmt]}\nEOF\n"
    )
    f = tmp_path / "tiny.tsp"
    f.write_text(text)
    D = read_tsplib(f).matrix()
    assert np.array_equal(D, [[0, 1, 2], [1, 0, 3], [2, 3, 0]])


def test_atsp_full_matrix(tmp_path: Path):
    f = tmp_path / "a.atsp"
    f.write_text(
        "NAME: a\nTYPE: ATSP\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EXPLICIT\n"
        "EDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n0 1 9\n9 0 1\n1 9 0\nEOF\n"
    )
    prob = read_tsplib(f)
    assert prob.type == "ATSP"
    s = solve_sequence(prob.matrix(), method="exact", closed=True)
    assert s.cost == 3.0


def test_errors_name_file_line_field(tmp_path: Path):
    f = tmp_path / "bad.tsp"
    f.write_text(
        "NAME: bad\nDIMENSION: 2\nEDGE_WEIGHT_TYPE: EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 x 1\n"
    )
    with pytest.raises(InputError, match=r"bad.tsp, line 6, field 'NODE_COORD_SECTION'"):
        read_tsplib(f)
    f.write_text("NAME: bad\nDIMENSION: 2\nNODE_COORD_SECTION\n1 0 0\n2 1 1\n")
    with pytest.raises(InputError, match="EDGE_WEIGHT_TYPE"):
        read_tsplib(f)
    f.write_text(
        "DIMENSION: 3\nEDGE_WEIGHT_TYPE: EXPLICIT\nEDGE_WEIGHT_FORMAT: UPPER_ROW\n"
        "EDGE_WEIGHT_SECTION\n1 2\nEOF\n"
    )
    with pytest.raises(InputError, match="needs 3 weights, found 2"):
        read_tsplib(f)
    f.write_text("DIMENSION: 2\nEDGE_WEIGHT_TYPE: XRAY\nNODE_COORD_SECTION\n1 0 0\n2 1 1\n")
    with pytest.raises(InputError, match="unsupported edge weight type"):
        read_tsplib(f)
    t = tmp_path / "bad.tour"
    t.write_text("DIMENSION: 3\nTOUR_SECTION\n1\n2\n2\n-1\nEOF\n")
    with pytest.raises(InputError, match="not a permutation"):
        read_tour(t)
    with pytest.raises(InputError, match="cannot read"):
        read_tsplib(tmp_path / "missing.tsp")
