"""The seeded split of the poses into fitting and withheld sets and cross-validation folds.

Poses with identical joint values (repeats) always stay on the same side. The withheld poses
are never used for fitting; they judge the final model, and choose it only between the search's
model and the complete geometric calibration (:mod:`zrp.gap.analysis.fallback`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from zrp.errors import InputError
from zrp.gap.data.measurements import Measurements

__all__ = ["MIN_POSES", "split_poses"]

#: fewest distinct poses the diagnosis accepts (a few hundred give a reliable answer).
MIN_POSES = 8


def split_poses(meas: Measurements, rng: np.random.Generator, withheld_fraction: float = 0.25,
                folds: int = 5) -> tuple[NDArray[np.int64], NDArray[np.int64],
                                         list[NDArray[np.int64]]]:
    """Seeded split by pose (repeats of a pose stay together).

    Returns:
        fitting pose indices, withheld pose indices, and the CV folds (a partition of the
        fitting poses).
    """
    if not 0.0 < withheld_fraction < 1.0:
        raise InputError(f"withheld_fraction: expected a value in (0, 1), got {withheld_fraction}")
    if folds < 2:
        raise InputError(f"folds: expected at least 2 cross-validation folds, got {folds}")
    groups = meas.repeat_groups()
    ng = int(groups.max()) + 1
    order = rng.permutation(ng)
    n_with = max(1, round(withheld_fraction * ng))
    if ng - n_with < 2:
        raise InputError(f"only {ng} distinct poses: too few to withhold any; measure at least "
                         f"{MIN_POSES} distinct poses")
    withheld_groups = set(order[:n_with].tolist())
    is_with = np.array([g in withheld_groups for g in groups])
    fitting = np.flatnonzero(~is_with)
    withheld = np.flatnonzero(is_with)
    fit_groups = order[n_with:]
    fold_of_group = {int(g): i % folds for i, g in enumerate(fit_groups)}
    fold_id = np.array([fold_of_group[int(groups[p])] for p in fitting])
    fold_list = [fitting[fold_id == f] for f in range(folds) if np.any(fold_id == f)]
    return fitting, withheld, fold_list
