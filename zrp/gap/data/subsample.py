"""Large measurement files: the stated, seeded rule by which the diagnosis keeps a subsample.

The diagnosis's cost grows faster than linearly with the number of measured points (its
cross-validated search refits every candidate on every fold: on this 2-core machine 3,000
points take about 5 s and 10,000 about 30 s), so beyond :data:`MAX_POINTS` points it works on
a random subsample of whole poses instead of running for hours:

* poses with identical joint values (repeats) form one group and are kept or dropped
  together, so the noise floor from repeats survives;
* the groups are put in the order of ``numpy.random.default_rng(seed).permutation`` and taken
  from the front while the kept points stay within the limit (at least one group);
* the kept poses stay in measurement order (approach directions and drift are preserved).

The rule is announced in a :class:`~zrp.gap.data.measurements.DataWarning` (printed by the
command line, recorded in ``diagnosis.json`` under ``warnings``); ``max_points=None`` uses every
point.
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray

from zrp.arguments import check_int
from zrp.gap.data.choices import MAX_POINTS
from zrp.gap.data.measurements import DataWarning, Measurements

__all__ = ["MAX_POINTS", "subsample_poses"]



def subsample_poses(meas: Measurements, max_points: int | None, seed: int
                    ) -> tuple[Measurements, NDArray[np.int64] | None]:
    """The measurements the diagnosis uses, and the indices of the kept poses into
    ``meas.pose_ids`` (None when every pose is kept).

    Args:
        meas: all measurements.
        max_points: most rows kept (>= 1), or None for all.
        seed: seed of the permutation of the repeat groups (the diagnosis's ``seed``).
    """
    if max_points is None or meas.n_rows <= max_points:
        return meas, None
    check_int(max_points, "max_points", 1)
    groups = meas.repeat_groups()                         # (P,) group per pose
    rows_per_pose = np.bincount(meas.pose_index, minlength=len(meas.pose_ids))
    rows_per_group = np.bincount(groups, weights=rows_per_pose)
    order = np.random.default_rng(seed).permutation(rows_per_group.size)
    total = np.cumsum(rows_per_group[order])
    take = max(1, int(np.searchsorted(total, max_points, side="right")))
    keep_group = np.zeros(rows_per_group.size, dtype=bool)
    keep_group[order[:take]] = True
    keep_pose = keep_group[groups]
    sub = meas.subset(keep_pose)
    warnings.warn(
        f"{meas.source}: {meas.n_rows} measured points ({len(meas.pose_ids)} poses) exceed "
        f"max_points={max_points}: the diagnosis uses {sub.n_rows} points of "
        f"{len(sub.pose_ids)} poses, whole poses drawn at random (repeats together; "
        f"numpy.random.default_rng({seed}).permutation of the {rows_per_group.size} repeat "
        "groups, taken in that order up to the limit), in measurement order. Pass "
        "max_points=None (--max-points 0 on the command line) to use every point (the time "
        "grows faster than linearly)", DataWarning, stacklevel=3)
    return sub, np.flatnonzero(keep_pose)
