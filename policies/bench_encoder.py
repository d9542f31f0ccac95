"""`legged bench encoder`: what a PPO mini-batch's history encoder costs on this CPU.

Times a forward and backward pass of `HistoryConv` on one mini-batch for several history lengths, beside the
same pass through `torch.nn.functional.conv1d` (the reference layout) and through the actor's MLP head alone,
and reports each as a ratio in the one run (absolute times differ between machines and loads).
"""

from __future__ import annotations

import time

import torch

from policies.latent_models import HistoryConv


def conv1d_reference(encoder: HistoryConv, history: torch.Tensor) -> torch.Tensor:
    """`encoder(history)` computed with channel-first `conv1d` layers (for tests and this benchmark)."""
    x = encoder.activation(encoder.embed(history.reshape(-1, encoder.steps, encoder.features))).transpose(1, 2)
    for conv, (kernel, stride, skip) in zip(encoder.convs, encoder.windows):
        weight = conv.weight.reshape(conv.out_features, -1, kernel)
        x = encoder.activation(torch.nn.functional.conv1d(x[..., skip:], weight, conv.bias, stride))
    return encoder.output(x.transpose(1, 2).flatten(1)).reshape(*history.shape[:-1], -1)


def _seconds(fn, repeats: int) -> float:
    fn()  # warm-up
    start = time.perf_counter()
    for _ in range(repeats):
        fn()
    return (time.perf_counter() - start) / repeats


def bench_encoders(steps: list[int], batch: int = 6144, features: int = 45, latent: int = 32,
                   hidden: tuple = (128, 128, 128), repeats: int = 4, seed: int = 0) -> list[dict]:
    """One record per history length: seconds per forward + backward pass of the encoder (unfold layout and
    conv1d layout) and of the head alone, and their ratios."""
    torch.manual_seed(seed)
    layers, width = [], features + latent // 2
    for size in hidden:
        layers += [torch.nn.Linear(width, size), torch.nn.ELU()]
        width = size
    head = torch.nn.Sequential(*layers, torch.nn.Linear(width, 12))
    head_s = _seconds(lambda: head(torch.randn(batch, features + latent // 2)).sum().backward(), repeats)
    records = []
    for n in steps:
        encoder, history = HistoryConv(n, features, latent), torch.randn(batch, n * features)
        unfold_s = _seconds(lambda: encoder(history).sum().backward(), repeats)
        conv1d_s = _seconds(lambda: conv1d_reference(encoder, history).sum().backward(), repeats)
        records.append({"history_steps": n, "batch": batch, "threads": torch.get_num_threads(),
                        "encoder_s": unfold_s, "conv1d_s": conv1d_s, "head_s": head_s,
                        "conv1d_over_unfold": conv1d_s / unfold_s, "encoder_over_head": unfold_s / head_s})
    return records
