"""The Held-Karp 1-tree bound against exact optima (Held-Karp DP) and TSPLIB's known optima."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import require_shared
from scipy.sparse.csgraph import minimum_spanning_tree

from weldplan.io.tsplib import read_tsplib
from weldplan.optim.discrete.bounds import one_tree, one_tree_bound
from weldplan.optim.discrete.sequence import solve_sequence


@pytest.mark.parametrize("n", [3, 6, 10, 14])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bound_is_below_the_exact_open_path_and_above_the_spanning_tree(n: int, seed: int):
    X = np.random.default_rng(seed).uniform(0, 100, (n, 3))
    D = np.linalg.norm(X[:, None] - X[None], axis=-1)
    opt = solve_sequence(D, method="exact").cost
    lb = one_tree_bound(D, open_path=True)
    assert lb <= opt * (1 + 1e-9)
    assert lb >= minimum_spanning_tree(D).sum() - 1e-9
    assert lb >= 0.97 * opt  # small Euclidean instances: the bound is nearly tight


def test_closed_tour_bound_on_a_square_is_its_perimeter():
    X = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    D = np.linalg.norm(X[:, None] - X[None], axis=-1)
    assert one_tree_bound(D, open_path=False) == pytest.approx(4.0)
    assert one_tree_bound(D, open_path=True) == pytest.approx(3.0)


def test_fewer_iterations_give_a_weaker_but_valid_bound():
    X = np.random.default_rng(3).uniform(0, 100, (60, 2))
    D = np.linalg.norm(X[:, None] - X[None], axis=-1)
    weak, strong = one_tree_bound(D, max_iter=1), one_tree_bound(D, max_iter=300)
    assert weak == pytest.approx(minimum_spanning_tree(D).sum())  # pi = 0: the MST + 0 + 0
    assert strong > 1.02 * weak


def test_a_spent_cpu_cap_is_reported_and_the_bound_stays_valid():
    X = np.random.default_rng(3).uniform(0, 100, (60, 2))
    D = np.linalg.norm(X[:, None] - X[None], axis=-1)
    free = one_tree(D)
    assert not free.clock_stopped and 1 < free.iterations <= 300
    assert free.bound == one_tree_bound(D)  # the float API is the same ascent
    capped = one_tree(D, max_seconds=0.0)  # one iteration (a finite bound), then the cap
    assert capped.clock_stopped and capped.iterations == 1
    assert capped.bound == pytest.approx(minimum_spanning_tree(D).sum())
    assert not one_tree(D, max_seconds=600.0).clock_stopped


@pytest.mark.parametrize("name", ["eil51", "berlin52", "st70"])
def test_tsplib_bound_within_a_few_percent_of_the_known_optimum(name: str):
    inst = read_tsplib(require_shared("tsplib", f"{name}.tsp"))
    known = {"eil51": 426, "berlin52": 7542, "st70": 675}[name]
    lb = one_tree_bound(inst.matrix(), open_path=False)
    assert lb <= known + 1e-6  # berlin52: the bound reaches the optimum
    assert lb >= 0.97 * known


def test_bad_shape():
    with pytest.raises(ValueError, match="square"):
        one_tree_bound(np.zeros((3, 2)))


def test_dense_mst_matches_scipy() -> None:
    from weldplan.optim.discrete.bounds import dense_mst

    rng = np.random.default_rng(3)
    P = rng.uniform(0, 100, size=(60, 3))
    W = np.linalg.norm(P[:, None] - P[None], axis=2)
    total, parent = dense_mst(W)
    assert total == pytest.approx(float(minimum_spanning_tree(W).sum()), rel=1e-12)
    assert parent[0] == -1 and (parent[1:] >= 0).all()
    assert total == pytest.approx(float(W[np.arange(1, 60), parent[1:]].sum()), rel=1e-12)
