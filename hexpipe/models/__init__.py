"""Terrain embedding: the convolutional VAE, its shared preprocessing and the frozen encoder PPO consumes.

The training stage lives in `hexpipe.models.train_vae` (the loop), with `vae_data` (the dataset), `probes` (what
the latent holds), `rise_head` (the training-only aux head of `vae.feature_weight`) and `vae_report` (figures); all
imported on demand: they pull in dvclive, matplotlib and the rollout reader, which the policy side does not need.
"""

from hexpipe.models.vae import (
    HEIGHTMAP_RANGE_M,
    ConvVAE,
    EncoderError,
    FrozenEncoder,
    Normalisation,
    export_encoder,
    load_encoder,
    preprocess,
    vae_loss,
)

__all__ = [
    "HEIGHTMAP_RANGE_M",
    "ConvVAE",
    "EncoderError",
    "FrozenEncoder",
    "Normalisation",
    "export_encoder",
    "load_encoder",
    "preprocess",
    "vae_loss",
]
