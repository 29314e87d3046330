"""Loader of the planar ellipse drops of Fazeli et al. (ICRA 2017) from a user's copy.

Three MAT-5 files (``registry.FAZELI_2017``): ``data_ellipse.mat`` (the 1,718 processed
drops: states just before and after impact, the contact Jacobian rows ``n`` and ``d``),
``v_models.mat`` (six contact models' predicted speeds after impact for the same drops) and
``ellipse_uniform.mat`` (the 2,000 raw drops with their quality flags).

Two properties of the published files matter to anyone comparing with them (both checked
here against the raw file, not assumed):

* the processed ``v_y`` after impact is the raw one plus ``3 g h`` = 0.11772 m/s
  (g = 9.81, h = 1/250 s); the six models' predictions are pure impulse predictions (their
  change of speed lies in the span of ``M⁻¹ n`` and ``M⁻¹ d`` to round-off);
* ``n`` and ``d`` are evaluated at the pose one frame before impact, not at ``states_i``'s
  angle; they are used as given (they are what the six models were run with).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import registry
from .records import MeasuredImpacts

#: The ellipse (the paper's Section on the experimental setup): mass, semi-axes.
MASS = 0.0364  # kg
SEMI_AXES = (0.035, 0.025)  # m
#: Gravity over three frames at 250 Hz: the offset of the processed post-impact v_y.
POST_VY_OFFSET = 3 * 9.81 / 250
#: The six models of ``v_models.mat``, three columns each, in the dataset's published order.
MODEL_NAMES = ("Drumwright-Shell", "AP Poisson", "AP Newton", "Mirtich", "Wang-Mason",
               "Whittaker")
RAW_DROPS = 2000


def mass_matrix() -> np.ndarray:
    """diag(m, m, I) with I = m (a² + b²)/5, a uniform elliptic disk."""
    a, b = SEMI_AXES
    return np.diag([MASS, MASS, MASS * (a * a + b * b) / 5])


@dataclass(frozen=True)
class FazeliData:
    impacts: MeasuredImpacts  # the processed drops, post-impact v_y as published
    model_speeds: dict[str, np.ndarray]  # model name -> (N, 3) predicted speeds after
    raw_flags: np.ndarray  # (2000, 6) bool, columns as registry.FAZELI_2017.quality_flags
    hashes: dict[str, str]  # file name -> SHA-256 (empty when not checked)
    directory: Path
    pre_impact_angles: np.ndarray  # (N,) θ of states_i (the Jacobians are of an earlier pose)

    def flag_counts(self) -> dict[str, int]:
        names = [name for name, _ in registry.FAZELI_2017.quality_flags]
        return {name: int(count) for name, count in zip(names, self.raw_flags.sum(axis=0))}

    def provenance(self) -> dict:
        return registry.provenance(registry.FAZELI_2017, self.directory, self.hashes)


def _loadmat(path: Path) -> dict:
    import scipy.io  # the field's standard reader of MAT-5 files (no code is run)
    from scipy.io.matlab import MatReadError

    try:
        return scipy.io.loadmat(path)
    except (MatReadError, ValueError, TypeError, OSError) as error:
        raise registry.DataInvalid(f"{path}: not a readable MAT-5 file ({error})") from None


def _array(path: Path, name: str, value, columns: int) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.ndim != 2 or array.shape[1] != columns or not np.all(np.isfinite(array)):
        raise registry.DataInvalid(f"{path}: field {name}: shape {array.shape}, expected "
                                   f"finite values in (N, {columns})")
    return array


def load(directory: Path, check_hashes: bool = True) -> FazeliData:
    """Read the three files of ``directory`` (hashes checked first unless ``check_hashes``
    is False, for synthetic files in the same layout). Raises ``registry.DataInvalid``
    naming the file, the field and what was expected."""
    directory = Path(directory)
    dataset = registry.FAZELI_2017
    hashes = registry.verify(dataset, directory) if check_hashes else {}
    path = directory / "data_ellipse.mat"
    try:
        data = _loadmat(path)["data"][0, 0]
        fields = {name: data[name] for name in ("states_i", "states_f", "n", "d")}
    except (KeyError, IndexError, ValueError) as error:
        raise registry.DataInvalid(f"{path}: expected a struct 'data' with fields states_i, "
                                   f"states_f, n, d ({error})") from None
    before = _array(path, "states_i", fields["states_i"], 6)
    after = _array(path, "states_f", fields["states_f"], 6)
    wn, wt = _array(path, "n", fields["n"], 3), _array(path, "d", fields["d"], 3)
    drops = before.shape[0]
    if not after.shape[0] == wn.shape[0] == wt.shape[0] == drops:
        raise registry.DataInvalid(f"{path}: states_i, states_f, n, d differ in row count")

    path = directory / "v_models.mat"
    try:
        predictions = _array(path, "v_models", _loadmat(path)["v_models"], 3 * len(MODEL_NAMES))
    except KeyError:
        raise registry.DataInvalid(f"{path}: no field v_models") from None
    if predictions.shape[0] != drops:
        raise registry.DataInvalid(f"{path}: v_models has {predictions.shape[0]} rows, "
                                   f"data_ellipse.mat {drops}")
    model_speeds = {name: predictions[:, 3 * k:3 * k + 3] for k, name in enumerate(MODEL_NAMES)}

    path = directory / "ellipse_uniform.mat"
    try:
        raw = _loadmat(path)["bounce_array"][0]
        raw_states = np.stack([np.ravel(drop["states"]) for drop in raw]).astype(float)
        flags = np.stack([np.ravel(drop["flags"]) for drop in raw]) != 0
    except (KeyError, IndexError, ValueError) as error:
        raise registry.DataInvalid(f"{path}: expected a struct array 'bounce_array' with "
                                   f"fields states (12) and flags (6) ({error})") from None
    if raw_states.shape[1] != 12 or flags.shape[1] != 6:
        raise registry.DataInvalid(f"{path}: states {raw_states.shape}, flags {flags.shape}: "
                                   "expected 12 and 6 columns")
    clean = np.flatnonzero(~flags.any(axis=1))
    # The processed drops are the raw drops with every flag 0, in order: check it on the
    # speeds before impact and on the published post-impact offset.
    if clean.size != drops or not np.array_equal(raw_states[clean, 3:6], before[:, 3:6]):
        raise registry.DataInvalid(f"{path}: the drops with every flag 0 ({clean.size}) are "
                                   f"not data_ellipse.mat's {drops} drops")
    offset = after[:, 3:6] - raw_states[clean, 9:12]
    expected = np.array([0.0, POST_VY_OFFSET, 0.0])
    if not np.allclose(offset, expected, rtol=0, atol=1e-6):
        raise registry.DataInvalid(f"{path}: the processed speeds after impact differ from the "
                                   f"raw ones by {offset.min(axis=0)}..{offset.max(axis=0)}, "
                                   f"not the published offset {expected}")
    impacts = MeasuredImpacts("fazeli2017", mass_matrix(), before[:, 3:6].copy(),
                              after[:, 3:6].copy(), wn, wt, clean + 1)
    return FazeliData(impacts, model_speeds, flags, hashes, directory, before[:, 2].copy())


def without_post_offset(impacts: MeasuredImpacts) -> MeasuredImpacts:
    """The same drops with the raw post-impact v_y (the processed one less 3 g h)."""
    after = impacts.speeds_after - np.array([0.0, POST_VY_OFFSET, 0.0])
    return MeasuredImpacts(impacts.source + " (raw post-impact v_y)", impacts.mass_matrix,
                           impacts.speeds_before, after, impacts.wn, impacts.wt,
                           impacts.drop_ids)
