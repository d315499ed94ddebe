"""Legends drawn into images (issue 35): a scale bar under a false-colour image (the palette's
colours from one end to the other, the numbers of the ends below it), and a row of swatches that
says which colour is which tree depth in the box overlay. Numbers are drawn with a 3×5 pixel font,
so no imaging library is needed and every bar pixel is exactly a palette colour."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from . import palette

# 3×5 glyphs, row by row ('#' lit).
_GLYPHS = {
    "0": ("###", "#.#", "#.#", "#.#", "###"),
    "1": (".#.", "##.", ".#.", ".#.", "###"),
    "2": ("###", "..#", "###", "#..", "###"),
    "3": ("###", "..#", ".##", "..#", "###"),
    "4": ("#.#", "#.#", "###", "..#", "..#"),
    "5": ("###", "#..", "###", "..#", "###"),
    "6": ("###", "#..", "###", "#.#", "###"),
    "7": ("###", "..#", ".#.", ".#.", ".#."),
    "8": ("###", "#.#", "###", "#.#", "###"),
    "9": ("###", "#.#", "###", "..#", "###"),
    ".": ("...", "...", "...", "...", ".#."),
    "-": ("...", "...", "###", "...", "..."),
    "+": ("...", ".#.", "###", ".#.", "..."),
    "e": ("...", "###", "#.#", "##.", "###"),
    " ": ("...", "...", "...", "...", "..."),
}
#: Pixels per font pixel, and the strip's sizes (pixels).
SCALE = 2
TEXT_HEIGHT = 5 * SCALE
BAR_HEIGHT = 12
MARGIN = 4
#: Background of a legend strip (linear RGB): dark grey, away from every ramp colour.
BACKGROUND = (0.02, 0.02, 0.02)
TEXT_COLOR = (1.0, 1.0, 1.0)


def number_text(value: float) -> str:
    """A short label for a number: integers as they are, others with 3 significant digits."""
    if float(value).is_integer() and abs(value) < 1e7:
        return str(int(value))
    return f"{value:.3g}"


def text_mask(text: str) -> np.ndarray:
    """(TEXT_HEIGHT, width) bool: the lit pixels of `text` (characters outside the font: ValueError)."""
    cols = []
    for ch in text:
        glyph = _GLYPHS.get(ch)
        if glyph is None:
            raise ValueError(f"the legend font has no {ch!r}")
        cols.append(np.array([[c == "#" for c in row] for row in glyph]))
        cols.append(np.zeros((5, 1), bool))  # spacing
    mask = np.concatenate(cols[:-1], axis=1) if cols else np.zeros((5, 0), bool)
    return np.kron(mask, np.ones((SCALE, SCALE), bool)).astype(bool)


def blank_strip(height: int, width: int) -> np.ndarray:
    """(height, width, 4) of the legend background."""
    out = np.ones((height, width, 4), np.float32)
    out[..., :3] = BACKGROUND
    return out


def draw_text(image: np.ndarray, text: str, x: int, y: int) -> None:
    """Light the pixels of `text` in TEXT_COLOR, its top left at (x, y) (moved left to fit)."""
    mask = text_mask(text)
    h, w = mask.shape
    x = int(np.clip(x, 0, max(image.shape[1] - w, 0)))
    region = image[y : y + h, x : x + w]
    region[mask[: region.shape[0], : region.shape[1]], :3] = TEXT_COLOR


def bar_colors(width: int, colors: Callable[[np.ndarray], np.ndarray], lo: float, hi: float) -> np.ndarray:
    """(width, 3): the colours of the bar's columns, `colors` of values evenly from lo to hi."""
    return colors(np.linspace(lo, hi, width, dtype=np.float32))


def scale_bar(width: int, lo: float, hi: float, colors: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """(h, width, 4) strip: a bar of `colors` (a palette of values lo..hi) from column MARGIN to
    width - MARGIN, the numbers lo (left) and hi (right) below it."""
    strip = blank_strip(MARGIN + BAR_HEIGHT + MARGIN + TEXT_HEIGHT + MARGIN, width)
    inner = max(width - 2 * MARGIN, 1)
    strip[MARGIN : MARGIN + BAR_HEIGHT, MARGIN : MARGIN + inner, :3] = bar_colors(inner, colors, lo, hi)[None]
    y = MARGIN + BAR_HEIGHT + MARGIN
    draw_text(strip, number_text(lo), MARGIN, y)
    hi_text = number_text(hi)
    draw_text(strip, hi_text, width - MARGIN - text_mask(hi_text).shape[1], y)
    return strip


def heat_bar(width: int, lo: float, hi: float) -> np.ndarray:
    """scale_bar of the heat ramp over lo..hi (a counter's legend)."""
    return scale_bar(width, lo, hi, lambda v: palette.heat(palette.scaled(v, lo, hi)))


def diverging_bar(width: int, span: float) -> np.ndarray:
    """scale_bar of the diverging ramp over -span..span (a difference's legend)."""
    return scale_bar(width, -span, span, lambda v: palette.diverging(v / span))


def depth_legend(width: int, depths) -> np.ndarray:
    """(h, width, 4) strip: one swatch per tree depth in the overlay's depth colour, its number
    below; as many as fit (the last ones are left out where they do not)."""
    depths = [int(d) for d in depths]
    swatch = max(TEXT_HEIGHT * 2, text_mask(number_text(max(depths, default=0))).shape[1] + 2)
    fit = max((width - MARGIN) // (swatch + MARGIN), 1)
    shown = depths[:fit]
    strip = blank_strip(MARGIN + BAR_HEIGHT + MARGIN + TEXT_HEIGHT + MARGIN, width)
    colors = palette.depth(np.array(shown, np.uint32)) if shown else np.zeros((0, 3), np.float32)
    for k, (d, c) in enumerate(zip(shown, colors)):
        x = MARGIN + k * (swatch + MARGIN)
        strip[MARGIN : MARGIN + BAR_HEIGHT, x : x + swatch, :3] = c
        draw_text(strip, number_text(d), x, MARGIN + BAR_HEIGHT + MARGIN)
    return strip


def below(image: np.ndarray, strip: np.ndarray) -> np.ndarray:
    """`image` with `strip` under it (same width)."""
    return np.concatenate([image, strip], axis=0)


def render_legends(
    image: np.ndarray, options, heatmap_scale: float | None = None, tree_height: int | None = None
) -> np.ndarray:
    """A rendered image with the legends of its colourings under it: the heat bar of the heatmap
    mode (0 to `heatmap_scale` box tests, the render's timings["heatmap_scale"]), and the depth
    swatches of boxes coloured by depth (the depths the tree has, where `tree_height` is given).
    `options`: the render's bvhlab.RenderOptions."""
    width = image.shape[1]
    if options.mode == "heatmap":
        if heatmap_scale is None:
            raise ValueError("a heatmap's legend needs its scale (the render's timings['heatmap_scale'])")
        image = below(image, heat_bar(width, 0.0, float(heatmap_scale)))
    if options.overlay_depth is not None and options.color_by_depth:
        lo, hi = options.overlay_depth
        hi = hi if tree_height is None else min(hi, tree_height - 1)
        if lo <= hi:  # no strip for a range past the tree's deepest boxes: nothing was drawn
            image = below(image, depth_legend(width, range(lo, hi + 1)))
    return image


def overlay_height(bvh) -> int:
    """The height of the tree whose boxes the overlay draws (a two-level tree's: its TLAS's)."""
    stats = bvh.stats
    return int(stats["tlas_height"] if "tlas_height" in stats else stats["height"])


def no_boxes_warning(height: int, depth_range: tuple[int, int]) -> str | None:
    """What the CLI says where a depth range lies below a tree of `height` (overlay_height): it
    draws no box, silently otherwise. None where it draws some (or the tree has no nodes)."""
    a, b = depth_range
    if height < 1 or a <= height - 1:
        return None
    return f"warning: the tree's deepest boxes are at depth {height - 1}: --bvh-depth {a}:{b} draws none"
