"""Terrain embedding: the convolutional VAE, its shared preprocessing and the frozen encoder PPO consumes.

The training stage lives in `hexpipe.models.train_vae` (imported on demand: it pulls in dvclive and the
rollout reader, which the policy side does not need).
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
