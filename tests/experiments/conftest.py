"""A synthetic copy of the Fazeli et al. (2017) files, written at test time in their MAT
layout from a known law plus noise (the real files may not be committed)."""

from __future__ import annotations

import numpy as np
import pytest

import planar_impact as pi
from harness.experiments import fazeli

TRUE_LAW, TRUE_MU, TRUE_E = "poisson", 0.3, 0.7


def ellipse_contact(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """w_n, w_t of the ellipse's lowest point at angle θ (speeds v_x, v_y, ω): the point
    p = (p_x, p_y) from the centre moves with v + ω × p = (v_x − ω p_y, v_y + ω p_x)."""
    a, b = fazeli.SEMI_AXES
    phi = np.arctan2(-b * np.cos(theta), -a * np.sin(theta))  # minimises the height
    px = a * np.cos(phi) * np.cos(theta) - b * np.sin(phi) * np.sin(theta)
    py = a * np.cos(phi) * np.sin(theta) + b * np.sin(phi) * np.cos(theta)
    ones, zeros = np.ones_like(theta), np.zeros_like(theta)
    return np.stack([zeros, ones, px], axis=1), np.stack([ones, zeros, -py], axis=1)


def write_synthetic(directory, drops: int = 240, flagged: int = 40, noise: float = 0.02,
                    seed: int = 1) -> dict:
    """The three files in ``directory``: ``drops`` clean drops of TRUE_LAW with Gaussian
    noise (``noise`` m/s on v_x, v_y; ``noise``/0.03 rad/s on ω) and ``flagged`` flagged raw
    drops among them. Returns the truth."""
    import scipy.io

    rng = np.random.default_rng(seed)
    theta = rng.uniform(-np.pi, np.pi, drops)
    wn, wt = ellipse_contact(theta)
    before = np.stack([rng.uniform(-0.6, 0.6, drops), rng.uniform(-3.0, -2.2, drops),
                       rng.uniform(-8, 8, drops)], axis=1)
    matrix = fazeli.mass_matrix()
    after = np.empty_like(before)
    for i in range(drops):
        result = pi.solve(mass_matrix=matrix, wn=wn[i], wt=wt[i], u=before[i], mu=TRUE_MU,
                          e=TRUE_E, law=TRUE_LAW)
        after[i] = before[i] + result.delta_u
    after += rng.normal(0.0, noise, after.shape) * np.array([1.0, 1.0, 1 / 0.03])
    positions = np.zeros((drops, 3))
    positions[:, 2] = theta + rng.normal(0.0, 0.02, drops)  # the real θ differs a frame's worth
    states_i = np.hstack([positions, before])
    # the law's answer is the published frame (the default); the raw file holds it less 3gh
    raw = after - np.array([0.0, fazeli.POST_VY_OFFSET, 0.0])
    states_f = np.hstack([positions, after])
    data = {"states_i": states_i, "states_f": states_f, "n": wn, "d": wt}
    scipy.io.savemat(directory / "data_ellipse.mat", {"data": data})
    v_models = np.hstack([after] * len(fazeli.MODEL_NAMES))
    scipy.io.savemat(directory / "v_models.mat", {"v_models": v_models})
    total = drops + flagged
    raw_rows = np.sort(rng.choice(total, drops, replace=False))
    dtype = [("states", "O"), ("n", "O"), ("d", "O"), ("flags", "O")]
    bounce = np.empty((1, total), dtype=dtype)
    clean = iter(range(drops))
    for row in range(total):
        if row in raw_rows:
            i = next(clean)
            bounce[0, row] = (np.hstack([states_i[i], positions[i], raw[i]])[None],
                              wn[i][None], wt[i][None], np.zeros((1, 6), np.uint8))
        else:
            flags = np.zeros((1, 6), np.uint8)
            flags[0, rng.integers(0, 6)] = 1
            bounce[0, row] = (rng.normal(size=(1, 12)), wn[0][None], wt[0][None], flags)
    scipy.io.savemat(directory / "ellipse_uniform.mat", {"bounce_array": bounce})
    return {"law": TRUE_LAW, "mu": TRUE_MU, "e": TRUE_E, "drops": drops, "flagged": flagged}


@pytest.fixture(scope="module")
def synthetic_copy(tmp_path_factory):
    directory = tmp_path_factory.mktemp("fazeli_synthetic")
    truth = write_synthetic(directory)
    return directory, truth


@pytest.fixture(autouse=True)
def own_cache(tmp_path, monkeypatch):
    """Each test's ``experiments`` and ``calibrate`` keep their results in a cache of their
    own (never the project's)."""
    cache = tmp_path / "cache"
    monkeypatch.setenv("IMPACT_HARNESS_CACHE_DIR", str(cache))
    return cache
