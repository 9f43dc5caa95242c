"""Optimal assignment (Hungarian / Kuhn-Munkres) for small rectangular cost matrices, pure numpy.

Used to match tracks to detections; sizes are a handful of people, so O(n³) is nothing.
"""

from __future__ import annotations

import numpy as np

INFEASIBLE = 1e6
"""Cost meaning "these two must not be matched"."""


def _hungarian_rows_le_cols(cost: np.ndarray) -> list[int]:
    """For an n x m matrix with n <= m: the column assigned to each row (minimum total)."""
    n, m = cost.shape
    u = np.zeros(n + 1)
    v = np.zeros(m + 1)
    p = np.zeros(m + 1, dtype=int)  # p[j] = row (1-based) matched to column j
    way = np.zeros(m + 1, dtype=int)
    for i in range(1, n + 1):
        p[0] = i
        j0 = 0
        minv = np.full(m + 1, np.inf)
        used = np.zeros(m + 1, dtype=bool)
        while True:
            used[j0] = True
            i0 = p[j0]
            cur = cost[i0 - 1] - u[i0] - v[1:]
            free = ~used[1:]
            better = free & (cur < minv[1:])
            minv[1:][better] = cur[better]
            way[1:][better] = j0
            candidates = np.where(free, minv[1:], np.inf)
            j1 = int(np.argmin(candidates)) + 1
            delta = candidates[j1 - 1]
            u[p[used]] += delta
            v[used] -= delta
            minv[1:][free] -= delta
            j0 = j1
            if p[j0] == 0:
                break
        while True:
            j1 = way[j0]
            p[j0] = p[j1]
            j0 = j1
            if j0 == 0:
                break
    assignment = [-1] * n
    for j in range(1, m + 1):
        if p[j]:
            assignment[p[j] - 1] = j - 1
    return assignment


def assign(cost: np.ndarray, max_cost: float = INFEASIBLE / 2) -> list[tuple[int, int]]:
    """Minimum-cost matching of rows to columns; pairs costing more than ``max_cost`` are dropped.

    Returns:
        (row, column) pairs, sorted by row. Rows/columns left out are unmatched.
    """
    cost = np.asarray(cost, dtype=np.float64)
    if cost.ndim != 2 or cost.size == 0:
        return []
    cost = np.where(np.isfinite(cost), cost, INFEASIBLE)
    if cost.shape[0] <= cost.shape[1]:
        pairs = list(enumerate(_hungarian_rows_le_cols(cost)))
    else:
        cols = _hungarian_rows_le_cols(cost.T)
        pairs = sorted((r, c) for c, r in enumerate(cols))
    return [(r, c) for r, c in pairs if c >= 0 and cost[r, c] <= max_cost]
