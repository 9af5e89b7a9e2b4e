"""What the encoders tell apart near a block's face, where the lift has to start.

    .venv/bin/python reports/experiments/encoder_draw/near_probe.py data/sweeps/encoder_draw/encoders/seed*-*/

All the folders must hold encoders of one modality and image size (the first one's are used). For each encoder
folder (with its checkpoint.pt and encoder.json, as train-vae leaves them) it rebuilds the VAE,
takes the latent means of every frame of data/rollouts and, on the encoder's own held-out episodes (the split of
its vae.seed, as train-vae made it), scores linear read-outs fitted on its training episodes:
- `lift_zone`: logistic probe for "a rise 0-0.3 m ahead" (the zone of issue 10's adaptation figure) against every
  other frame, as accuracy, its majority baseline, and the share of the baseline's errors it removes;
- `near_r2`: ridge R² of the distance to the rise over frames with one 0-0.6 m ahead;
- `distance_r2`, `height_r2`: train-vae's own probes (frames with a rise in the map's reach), for reference.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import torch

from hexpipe.config import VaeConfig
from hexpipe.models.probes import linear_probe, ridge_r2
from hexpipe.models.train_vae import latent_means
from hexpipe.models.vae import ConvVAE, channels_for
from hexpipe.models.vae_data import load_dataset, split_by_episode

LIFT_ZONE_M = 0.3
NEAR_M = 0.6


def encoder_scores(folder: Path, data, val_fraction: float) -> dict[str, float]:
    config = json.loads((folder / "encoder.json").read_text())
    model = ConvVAE(channels_for(config["modality"]), int(config["image_size"]), int(config["latent_dim"]))
    state = torch.load(folder / "checkpoint.pt", map_location="cpu", weights_only=True)
    model.load_state_dict(state["model"])
    train, val = split_by_episode(data, val_fraction, int(config["seed"]))
    mu_train, mu_val = latent_means(model, data, train), latent_means(model, data, val)
    distance = data.rise_distance
    zone = np.isfinite(distance) & (distance >= 0) & (distance <= LIFT_ZONE_M)
    accuracy, baseline = linear_probe(mu_train, zone[train], mu_val, zone[val])
    near_t = np.isfinite(distance[train]) & (distance[train] <= NEAR_M)
    near_v = np.isfinite(distance[val]) & (distance[val] <= NEAR_M)
    in_t, in_v = np.isfinite(distance[train]), np.isfinite(distance[val])
    return {
        "seed": int(config["seed"]),
        "lift_zone_accuracy": accuracy, "lift_zone_baseline": baseline,
        "lift_zone_errors_removed": (accuracy - baseline) / (1 - baseline),
        "near_r2": ridge_r2(mu_train[near_t], distance[train][near_t], mu_val[near_v], distance[val][near_v]),
        "distance_r2": ridge_r2(mu_train[in_t], distance[train][in_t], mu_val[in_v], distance[val][in_v]),
        "height_r2": ridge_r2(mu_train[in_t], data.rise_height[train][in_t], mu_val[in_v],
                              data.rise_height[val][in_v]),
    }


def main(folders: list[str]) -> None:
    torch.set_num_threads(1)
    first = json.loads((Path(folders[0]) / "encoder.json").read_text())  # the frames the encoders were trained on
    cfg = VaeConfig(modality=first["modality"], image_size=int(first["image_size"]))  # from data/rollouts
    data = load_dataset(cfg)
    for folder in folders:
        scores = encoder_scores(Path(folder), data, cfg.val_fraction)
        print(f"{Path(folder).name}: " + ", ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
                                                   for k, v in scores.items()), flush=True)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    main(sys.argv[1:])
