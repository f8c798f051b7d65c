#!/usr/bin/env python3
"""The MSE an oracle's sample placement would reach at equal spp, over a uniform one's.

The oracle knows each pixel's per-sample variance s_p^2 and gives pixel p n_p samples with
n_p = max(floor, lambda * s_p), the sum fixed at `spp` a pixel: that minimises the sum of
s_p^2 / n_p, the MSE of the pixels' means. Printed as a ratio to the uniform n_p = spp, for
the pixel-mean (box) image; an adaptive sampler's equal-spp ratio cannot beat it by placement
alone. The variances come from a long stratified render's `--aov variance` (the variance of
each pixel's mean, per channel), written as PFM:

    acr render scenes/S.pbrt --spp 256 --seed 11 --threads 2 --sampler stratified \
        --filter box -o S.pfm --aov variance=S-var.pfm
    python3 bench/tools/oracle_allocation.py S-var.pfm 256 8:2 16:4

Each budget is `spp:floor` (the floor is the uniform first stage every pixel gets).
`--counts=N.pfm` also scores a sampler's own placement, its `--aov spp` image, the same way:

    acr render scenes/S.pbrt --spp 8 --seed 1 --threads 2 --sampler cluster \
        --filter gaussian -o S8.exr --aov spp=N.pfm
    python3 bench/tools/oracle_allocation.py S-var.pfm 256 8:2 --counts=N.pfm

Needs numpy.
"""

import sys

import numpy as np


def read_pfm(path):
    """A PFM image as an (h, w, channels) float array, top row first."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    channels = 3 if kind == b"PF" else 1
    return data.reshape(height, width, channels)[::-1]


def oracle_ratio(sigma, spp, floor):
    """The oracle's MSE over the uniform one's at `spp` samples a pixel, `floor` at least."""
    lo, hi = 0.0, 1e12
    target = spp * sigma.size
    for _ in range(200):
        lam = (lo + hi) / 2
        if np.maximum(floor, lam * sigma).sum() > target:
            hi = lam
        else:
            lo = lam
    n = np.maximum(floor, lo * sigma)
    # A pixel without variance adds nothing, however few samples it gets.
    err = np.divide(sigma**2, n, out=np.zeros_like(sigma), where=sigma > 0)
    return float(err.sum() / ((sigma**2).sum() / spp))


def placement_ratio(sigma, counts):
    """The MSE of the pixel means with `counts` samples each over a uniform placement's."""
    spp = counts.mean()
    err = np.divide(sigma**2, counts, out=np.zeros_like(sigma), where=sigma > 0)
    return float(err.sum() / ((sigma**2).sum() / spp))


def main():
    counts = [a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--counts=")]
    args = [a for a in sys.argv[1:] if not a.startswith("--counts=")]
    if len(args) < 3 and not (len(args) == 2 and counts):
        sys.exit(__doc__)
    variance, rendered_spp = args[0], float(args[1])
    # Per-sample variance: the pixel mean's variance times its count, channels averaged.
    per_sample = read_pfm(variance).mean(axis=2) * rendered_spp
    sigma = np.sqrt(np.maximum(per_sample, 0.0)).ravel()
    print(f"{variance}: {np.mean(sigma == 0) * 100:.1f}% of pixels without variance")
    for budget in args[2:]:
        spp, floor = (float(x) for x in budget.split(":"))
        print(f"  {spp:g} spp, first stage {floor:g}: {oracle_ratio(sigma, spp, floor):.3f}")
    for path in counts:
        n = read_pfm(path)[..., 0].ravel().astype(np.float64)
        if n.shape != sigma.shape:
            sys.exit(f"{path}: {n.size} pixels, the variances {sigma.size}")
        corr = np.corrcoef(n, sigma)[0, 1]
        print(f"  {path} ({n.mean():g} spp): {placement_ratio(sigma, n):.3f}, counts ~ sigma {corr:.2f}")


if __name__ == "__main__":
    main()
