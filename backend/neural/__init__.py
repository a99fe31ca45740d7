"""Neural noise runtime (Maesumi et al. 2024): numpy + onnxruntime, no torch.

schedule   the diffusion noise schedule (pure functions)
sampler    DDIM over any ε-model callable, with a per-step callback
"""
