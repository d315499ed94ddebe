"""The child process of bvhlab.snapshot: builds the tree and draws with moderngl."""

from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from .._atomic import replacing


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("npz")
    ap.add_argument("--name", default="scene")
    ap.add_argument("--build", default="{}")
    ap.add_argument("--out", required=True)
    ap.add_argument("--depth", nargs=2, type=int)
    ap.add_argument("--sheet", action="store_true")
    ap.add_argument("--size", nargs=2, type=int, required=True)
    args = ap.parse_args(argv)

    import bvhlab

    from .._core import depth_colors
    from .raster import Rasterizer

    scene = bvhlab.Scene.load(args.npz).flattened()  # the raster draws one level of boxes
    bvh = bvhlab.build(scene, **json.loads(args.build))
    assert isinstance(bvh, bvhlab.Bvh)  # a flat scene gets a flat tree
    raster = Rasterizer(scene, *args.size)

    def boxes(a, b):
        lo, hi, depth = bvh.boxes(a, b)
        return lo, hi, depth_colors(depth.astype(np.uint32))

    height = bvh.stats["height"]
    if not args.sheet:
        from .. import legend

        warning = legend.no_boxes_warning(height, tuple(args.depth))
        if warning:  # drew nothing, silently (passed on by bvhlab.snapshot)
            print(warning, file=sys.stderr)
        image = raster.draw(*boxes(*args.depth))
        shown = range(args.depth[0], min(args.depth[1], height - 1) + 1)
        _save_srgb(with_depth_legend(image, shown), args.out)
        return
    panels = [
        (d, with_depth_legend(raster.draw(*boxes(d, d)), [d]), bvh.stats["nodes_per_depth"][d]) for d in range(height)
    ]
    _sheet(panels, args.out, f"{args.name}: {bvh.config.method} — boxes per depth (height {height})")


def with_depth_legend(image: np.ndarray, depths) -> np.ndarray:
    """The raster image (uint8) with the swatches of `depths` under it (bvhlab.legend.depth_legend),
    in the raster's own encoding: OpenGL writes the palette's floats into the RGBA8 target as they
    are (round(v × 255), no sRGB curve), so a swatch is the very byte value of its boxes' lines."""
    from .. import legend

    strip = legend.depth_legend(image.shape[1], depths)
    return np.concatenate([image, raster_bytes(strip)], axis=0)


def raster_bytes(image: np.ndarray) -> np.ndarray:
    """Linear float RGBA → the uint8 the raster's framebuffer holds for it."""
    return np.round(np.clip(image, 0.0, 1.0) * 255).astype(np.uint8)


def _save_srgb(image: np.ndarray, path) -> None:
    """The raster image is already display-referred 8-bit: write it as it is."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with replacing(path) as f:  # whole or not at all (issue 39.8)
        plt.imsave(f, image, format="png")


def _sheet(panels, path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = math.ceil(math.sqrt(len(panels) * 4 / 3))
    rows = math.ceil(len(panels) / cols)
    h, w = panels[0][1].shape[:2]
    fig, axes = plt.subplots(rows, cols, figsize=(cols * w / 100, rows * (h + 40) / 100 + 0.4), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, (depth, image, count) in zip(axes.flat, panels):
        ax.imshow(image, interpolation="nearest")  # the legend swatch keeps its exact colour
        ax.set_title(f"depth {depth}: {count} boxes", fontsize=8)
    fig.suptitle(title, fontsize=10)
    try:
        fig.tight_layout()
        with replacing(path) as f:  # whole or not at all (issue 39.8)
            fig.savefig(f, format="png", dpi=100)
    finally:
        plt.close(fig)


if __name__ == "__main__":
    try:
        main()
    except OSError as e:  # a file that cannot be read or written: one line, which the parent reports
        raise SystemExit(str(e)) from None
