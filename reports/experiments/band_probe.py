"""What a VAE's 8-d embedding holds about each part of the height map: ridge R² from the latent to the highest
terrain in each band of the map's rows (across the legs' corridor), rear to front, on the VAE's own held-out
episodes. The same figure as train-vae's `probe/profile_r2/bandK`, for any encoder.

    .venv/bin/python reports/experiments/band_probe.py --encoder data/models/vae   # after `make repro`

Bands and corridor are vae.profile_bands and vae.profile_corridor (8 bands of 0.25 m; the central 0.8 m). The hind
feet touch down about 0.5 m behind the base, the front feet about 0.5 m ahead of it.
"""

import argparse
from itertools import pairwise
from pathlib import Path

import numpy as np

from hexpipe.config import load_params
from hexpipe.models.probes import ridge_r2
from hexpipe.models.rise_head import terrain_profile
from hexpipe.models.vae import load_encoder
from hexpipe.recording.reader import iter_frames


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml")
    parser.add_argument("--encoder", action="append", help="encoder folder (repeatable; default ppo.encoder_dir)")
    args = parser.parse_args()
    params = load_params(Path(args.params))
    sensors, vae = params.sensors, params.vae
    frames = [f for f in iter_frames(Path(vae.data_dir), ("heightmap",)) if "heightmap" in f.sensors]
    maps = np.stack([f.sensors["heightmap"] for f in frames]).astype(np.float32)
    episodes = sorted({f.episode for f in frames})
    index = np.array([episodes.index(f.episode) for f in frames])
    # the VAE's own split (hexpipe.models.vae_data.split_by_episode): the same seeded share of episodes held out
    n_val = min(max(1, round(vae.val_fraction * len(episodes))), len(episodes) - 1)
    held_out = np.isin(index, np.random.default_rng(vae.seed).permutation(len(episodes))[:n_val])
    bands = terrain_profile(maps[:, None], vae.profile_bands, vae.profile_corridor)
    near, far = sensors.heightmap_ahead
    edges = np.linspace(near, far, vae.profile_bands + 1)
    print(f"{len(frames)} frames, {len(episodes)} episodes, {held_out.sum()} held-out frames ({n_val} episodes)")
    print("band (m from the base): " + " ".join(f"{a:+.2f}..{b:+.2f}" for a, b in pairwise(edges)))
    for folder in args.encoder or [params.ppo.encoder_dir]:
        encoder = load_encoder(folder)
        latents = np.concatenate([encoder.encode(maps[i : i + 512]) for i in range(0, len(maps), 512)])
        r2 = [ridge_r2(latents[~held_out], bands[~held_out, k], latents[held_out], bands[held_out, k])
              for k in range(vae.profile_bands)]
        print(f"{folder}: ridge R² " + " ".join(f"{v:11.2f}" for v in r2))


if __name__ == "__main__":
    main()
