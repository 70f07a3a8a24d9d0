"""latentpt: a differentiable path tracer that renders into the latent space of an image autoencoder.

    import latentpt
    scene = latentpt.Scene("scenes/cornell-box/scene.json")
    rgb = scene.render(spp=16)                         # (H, W, 3) float32
    model = latentpt.LatentScene.from_fit("fit-out")   # a fitted latent scene
    latent = model.render(spp=64)                      # (h, w, 16)

latentpt.torch.render_latent makes the latent render a torch autograd function whose backward is the
path-replay adjoint. docs/python.md.
"""
from ._latentpt import (Cancelled, EditSession, LatentScene, Scene, SceneError, Vae, fit,  # noqa: F401
                        refine, render_edits)

__all__ = ["Cancelled", "EditSession", "LatentScene", "Scene", "SceneError", "Vae", "fit", "refine", "render_edits"]
