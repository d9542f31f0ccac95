"""The linear probe of a latent: how much of the randomised dynamics a policy's representation holds."""

from __future__ import annotations

import numpy as np


def probe_r2(features: np.ndarray, targets: np.ndarray, groups: np.ndarray | None = None,
             ridge: float = 1e-3) -> float | None:
    """Mean R^2, over the target dimensions that vary, of a ridge regression (with bias) from `features` to
    `targets`, fitted on the samples of even `groups` (e.g. episode ids: one episode's samples never fall on
    both sides) and scored on the odd ones; without groups, the even and odd samples. None when no target
    varies or a side is (nearly) empty."""
    features, targets = np.asarray(features, np.float64), np.asarray(targets, np.float64)
    groups = np.arange(len(features)) if groups is None else np.asarray(groups)
    fit, test = groups % 2 == 0, groups % 2 == 1
    if fit.sum() < 2 or test.sum() < 2:
        return None
    varying = targets[fit].std(0) > 1e-9
    if not varying.any():
        return None
    mean, std = features[fit].mean(0), features[fit].std(0) + 1e-8
    x = np.concatenate([(features - mean) / std, np.ones((len(features), 1))], axis=1)
    y = targets[:, varying]
    a = x[fit].T @ x[fit] + ridge * len(x[fit]) * np.eye(x.shape[1])
    weights = np.linalg.solve(a, x[fit].T @ y[fit])
    residual = ((y[test] - x[test] @ weights) ** 2).sum(0)
    total = ((y[test] - y[test].mean(0)) ** 2).sum(0)
    return float(np.mean(1.0 - residual / np.maximum(total, 1e-12)))
