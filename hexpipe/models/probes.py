"""Probes of what the VAE's latent holds: linear and kNN classifiers for "block ahead", ridge and kNN regressions
for the next rise's distance and height, and the count of active latent dims. Pure NumPy/torch on latent means.
"""

from __future__ import annotations

import math

import numpy as np
import torch

PROBE_DISTANCE_M = 1.0  # "block ahead" label: obstacle_distance below this (the paper's figure 4)


def linear_probe(
    x_train: np.ndarray, y_train: np.ndarray, x_val: np.ndarray, y_val: np.ndarray, l2: float = 1e-3
) -> tuple[float, float]:
    """Logistic regression on standardised latents (L-BFGS, L2 on weights) -> (val accuracy, baseline).

    The baseline is the best constant predictor on val, max(p, 1 - p), so the probe must beat class imbalance.
    Both are NaN when there is nothing to fit or score.
    """
    if len(y_val) == 0 or len(y_train) == 0:
        return math.nan, math.nan
    mean, std = x_train.mean(0), x_train.std(0) + 1e-6
    xt = torch.from_numpy(((x_train - mean) / std).astype(np.float32))
    xv = torch.from_numpy(((x_val - mean) / std).astype(np.float32))
    yt = torch.from_numpy(y_train.astype(np.float32))
    w = torch.zeros(xt.shape[1], requires_grad=True)
    b = torch.zeros((), requires_grad=True)
    opt = torch.optim.LBFGS([w, b], lr=1.0, max_iter=200, line_search_fn="strong_wolfe")

    def closure() -> torch.Tensor:
        opt.zero_grad()
        loss = torch.nn.functional.binary_cross_entropy_with_logits(xt @ w + b, yt) + l2 * w.pow(2).sum()
        loss.backward()
        return loss

    opt.step(closure)
    with torch.no_grad():
        predicted = (xv @ w + b > 0).numpy()
    positive_rate = float(y_val.mean())
    return float((predicted == y_val.astype(bool)).mean()), max(positive_rate, 1.0 - positive_rate)


def ridge_predict(x_train: np.ndarray, y_train: np.ndarray, x_val: np.ndarray, l2: float = 1e-3) -> np.ndarray:
    """Ridge regression from standardised latents to y, fitted on train (closed form, intercept unpenalised, L2
    weight `l2` per frame); its predictions on x_val."""
    mean, std = x_train.mean(0), x_train.std(0) + 1e-6
    xt, xv = (x_train - mean) / std, (x_val - mean) / std
    offset = float(y_train.mean())
    gram = xt.T @ xt + l2 * len(xt) * np.eye(xt.shape[1])
    w = np.linalg.solve(gram, xt.T @ (y_train - offset))
    return xv @ w + offset


def ridge_r2(
    x_train: np.ndarray, y_train: np.ndarray, x_val: np.ndarray, y_val: np.ndarray, l2: float = 1e-3
) -> float:
    """R² on val of `ridge_predict`: 1 - SS_res / SS_tot with SS_tot around val's own mean, so 0 for predicting
    that mean and negative when worse. NaN when there is too little to fit or val has no spread."""
    if len(y_train) < 2 or len(y_val) < 2:
        return math.nan
    return r_squared(y_val, ridge_predict(x_train, y_train, x_val, l2))


def knn_r2(x_train: np.ndarray, y_train: np.ndarray, x_val: np.ndarray, y_val: np.ndarray, k: int = 5) -> float:
    """R² on val of a k-nearest-neighbour mean on standardised latents: is the target there at all, linearly
    readable or not (shown beside the ridge probe; PPO's MLP reads non-linear codes too)."""
    if len(x_val) < 2 or len(x_train) < k:
        return math.nan
    mean, std = x_train.mean(0), x_train.std(0) + 1e-6
    xt, xv = torch.from_numpy((x_train - mean) / std), torch.from_numpy((x_val - mean) / std)
    nearest = torch.cdist(xv, xt).topk(k, largest=False).indices.numpy()
    return r_squared(y_val, y_train[nearest].mean(axis=1))


def r_squared(y: np.ndarray, predicted: np.ndarray) -> float:
    """Coefficient of determination; NaN when y has no spread."""
    y, predicted = np.asarray(y, dtype=np.float64), np.asarray(predicted, dtype=np.float64)
    total = float(((y - y.mean()) ** 2).sum())
    return 1.0 - float(((y - predicted) ** 2).sum()) / total if total > 1e-12 else math.nan


def rise_probes(
    train_mu: np.ndarray, train_rise: tuple[np.ndarray, np.ndarray], val_mu: np.ndarray,
    val_rise: tuple[np.ndarray, np.ndarray],
) -> dict[str, float]:
    """Probes of what the gait needs, on held-out episodes: R² of the distance to the next rise ahead and of its
    height, ridge (linear) and kNN. Both only on frames with a rise within the height map's reach: with nothing
    ahead there is no distance or height to predict, so those frames are left out (and counted), and whether a
    rise is in range at all is a separate linear classification probe."""
    (train_d, train_h), (val_d, val_h) = train_rise, val_rise
    train_in, val_in = np.isfinite(train_d), np.isfinite(val_d)
    labelled_train, labelled_val = ~np.isnan(train_d), ~np.isnan(val_d)  # inf (no rise) is a label, nan is not
    accuracy, baseline = linear_probe(
        train_mu[labelled_train], train_in[labelled_train], val_mu[labelled_val], val_in[labelled_val]
    )
    out = {"rise_in_range_accuracy": accuracy, "rise_in_range_baseline": baseline}
    for name, train_y, val_y in (("rise_distance", train_d, val_d), ("rise_height", train_h, val_h)):
        tr, va = train_in & np.isfinite(train_y), val_in & np.isfinite(val_y)
        out[f"{name}_r2"] = ridge_r2(train_mu[tr], train_y[tr], val_mu[va], val_y[va])
        out[f"{name}_knn_r2"] = knn_r2(train_mu[tr], train_y[tr], val_mu[va], val_y[va])
    out["rise_val_frames"] = float(val_in.sum())
    out["rise_val_share"] = float(val_in.sum() / max(1, labelled_val.sum())) if labelled_val.any() else math.nan
    return out


def knn_accuracy(x_train: np.ndarray, y_train: np.ndarray, x_val: np.ndarray, y_val: np.ndarray, k: int = 5) -> float:
    """Accuracy of a k-nearest-neighbour vote on standardised latents: is the information there at all,
    linearly readable or not (shown beside the linear probe)."""
    if len(x_val) == 0 or len(x_train) < k:
        return float("nan")
    mean, std = x_train.mean(0), x_train.std(0) + 1e-6
    xt, xv = torch.from_numpy((x_train - mean) / std), torch.from_numpy((x_val - mean) / std)
    nearest = torch.cdist(xv, xt).topk(k, largest=False).indices.numpy()
    vote = y_train[nearest].mean(axis=1) > 0.5
    return float((vote == y_val.astype(bool)).mean())


def active_dims(mu: np.ndarray, threshold: float = 0.01) -> int:
    """Latent dims whose posterior mean varies across frames (Var > threshold, Burda et al. 2016).

    A collapsed dim carries ~no information to PPO even if the standardised linear probe can still read it,
    so this sits beside probe_accuracy in the metrics.
    """
    return int((mu.var(0) > threshold).sum()) if len(mu) > 1 else 0
