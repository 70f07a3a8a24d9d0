"""The latent render as a torch autograd function: forward renders the tone-mapped latent from the
model's raw parameters, backward runs latentpt's path-replay adjoint (docs/path-replay.md), so any
differentiable loss on the latent (a diffusion model's score distillation, a decoded-image loss)
moves scene parameters.

    import torch, latentpt, latentpt.torch as lt
    model = latentpt.LatentScene.from_fit("fit-out")
    raw = lt.raw_parameters(model)                # torch.nn.Parameter over every slice
    opt = torch.optim.SGD([raw], lr=0.1)
    latent = lt.render_latent(model, raw, spp=16, seed=it)   # (h, w, 16), differentiable
"""
import numpy as np
import torch

__all__ = ["render_latent", "raw_parameters", "slice_of"]


class _LatentRender(torch.autograd.Function):
    @staticmethod
    def forward(ctx, raw, model, width, height, spp, seed):
        raw_np = raw.detach().cpu().to(torch.float32).contiguous().numpy().copy()
        model.raw = raw_np
        linear = model.render_linear(width, height, spp, seed)
        ctx.model, ctx.raw, ctx.linear = model, raw_np, linear
        ctx.args = (width, height, spp, seed)
        ctx.device, ctx.dtype = raw.device, raw.dtype
        # on raw's device and in its dtype, as torch functions answer: a loss on the GPU (a
        # diffusion model's) takes the latent as it is, and gradcheck can run in float64
        return torch.from_numpy(model.tone(linear)).to(raw.device, raw.dtype)

    @staticmethod
    @torch.autograd.function.once_differentiable
    def backward(ctx, grad_latent):
        model = ctx.model
        model.raw = ctx.raw  # the parameters of the forward pass, whatever happened since
        d_linear = model.tone_backward(ctx.linear, grad_latent.detach().cpu().to(torch.float32).contiguous().numpy())
        grad_raw = model.backward_linear(d_linear, *ctx.args)
        return torch.from_numpy(np.asarray(grad_raw)).to(ctx.device, ctx.dtype), None, None, None, None, None


def render_latent(model, raw, width=0, height=0, spp=16, seed=0):
    """The tone-mapped latent (height, width, 16) of `model` with raw parameters `raw` (a 1-D
    tensor laid out as model.raw), on raw's device and in its dtype (computed in float32 on the
    CPU); 0 = the model's latent resolution. Differentiable in `raw`, once: the gradient itself
    is not differentiable. Both passes write `raw` into the model (model.raw): backward puts the
    forward pass's values back, so that the adjoint replays the paths the forward traced, and a
    model.raw = ... made between the two is undone by it."""
    if not isinstance(raw, torch.Tensor) or not raw.is_floating_point():
        # an integer tensor would come back as a latent truncated to integers, with no gradient
        raise TypeError("render_latent: raw must be a floating-point torch.Tensor, got "
                        + (str(raw.dtype) if isinstance(raw, torch.Tensor) else type(raw).__name__))
    return _LatentRender.apply(raw, model, width, height, spp, seed)


def raw_parameters(model):
    """The model's raw parameters as a torch.nn.Parameter (a copy: render_latent writes it back)."""
    return torch.nn.Parameter(torch.from_numpy(np.asarray(model.raw).copy()))


def slice_of(model, name):
    """Python slice of parameter `name` within raw (e.g. raw[slice_of(model, "floor.bsdf.reflectance")])."""
    for s in model.slices():
        if s["name"] == name:
            return slice(s["raw_offset"], s["raw_offset"] + s["raw_size"])
    raise KeyError(f"no parameter '{name}'")
