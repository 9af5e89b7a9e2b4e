"""The rise probes (ridge R² from the 8-d latent to the distance and height of the next rise ahead) of one or more
exported encoders, all on the same collected rollouts and the same train/val split by episode as train-vae's.

Tells a probe that dropped because the data got harder from one that dropped because the encoder got worse:

    .venv/bin/python reports/experiments/probe_encoders.py --data data/rollouts data/models/vae /tmp/old_vae
"""

import argparse
from pathlib import Path

import numpy as np
import torch

from hexpipe.config import VaeConfig
from hexpipe.models.probes import rise_probes
from hexpipe.models.vae import EncoderError, load_encoder
from hexpipe.models.vae_data import VaeDataError, load_dataset, split_by_episode


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("encoders", nargs="+", type=Path, help="folders holding encoder.pt and encoder.json")
    parser.add_argument("--data", type=Path, default=Path("data/rollouts"), help="collected rollouts (MCAP)")
    args = parser.parse_args()
    try:  # the encoders first: a wrong folder fails before the rollouts are read
        encoders = {folder: load_encoder(folder) for folder in args.encoders}
        cfg = VaeConfig(data_dir=str(args.data))
        data = load_dataset(cfg)
    except (EncoderError, VaeDataError) as exc:
        raise SystemExit(f"error: {exc}") from None
    train_idx, val_idx = split_by_episode(data, cfg.val_fraction, cfg.seed)
    print(f"{args.data}: {len(train_idx)} train / {len(val_idx)} val frames")
    for folder, encoder in encoders.items():
        net = encoder._net  # the dataset holds frames already preprocessed: the network, not encode()
        with torch.inference_mode():
            mu = {name: torch.cat([net(data.batch(idx[s:s + 512]))[0] for s in range(0, len(idx), 512)]).numpy()
                  for name, idx in (("train", train_idx), ("val", val_idx))}
        rise = rise_probes(mu["train"], (data.rise_distance[train_idx], data.rise_height[train_idx]),
                           mu["val"], (data.rise_distance[val_idx], data.rise_height[val_idx]))
        print(f"{folder}: " + ", ".join(f"{k} {v:.3f}" for k, v in rise.items() if np.isscalar(v)))


if __name__ == "__main__":
    main()
