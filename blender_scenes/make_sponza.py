"""Bundle Crytek Sponza (report Table 1, Figure 6) as blender_scenes/sponza.npz, losslessly:

    .venv/bin/python blender_scenes/make_sponza.py SOURCE.npy [--out blender_scenes/sponza.npz]

SOURCE.npy is the float32 (262205, 3, 3) triangle array the bundle was made from, as numpy's `.npy`
file (sha256 bvhlab.library.sponza.SOURCE_SHA256); the bundle gives it back bit for bit
(`np.save(path, sponza.load_triangles(bundle))`). Reads it, checks its sha256, welds exactly equal
vertices (bvhlab.library.sponza.weld) and writes an LZMA-compressed .npz that rebuilds the array bit
for bit (checked here, and again at every load); the same input gives the same bytes. Crytek
Sponza: Frank Meinl (Crytek), Morgan McGuire's version, CC BY 3.0 — see README.md beside this script.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from bvhlab.library import sponza

HERE = Path(__file__).resolve().parent


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("source", type=Path, help="the source triangle array (.npy, float32 (262205, 3, 3))")
    ap.add_argument("--out", type=Path, default=HERE / sponza.FILE_NAME)
    args = ap.parse_args()
    triangles = np.load(args.source, allow_pickle=False)
    if sponza.npy_sha256(triangles) != sponza.SOURCE_SHA256:
        print(f"error: {args.source} is not the expected Sponza array (sha256 differs)", file=sys.stderr)
        return 2
    sponza.write_bundle(triangles, args.out)
    again = sponza.load_triangles(args.out)  # the same check every load makes
    assert np.array_equal(again.view(np.uint32), triangles.view(np.uint32))
    print(
        f"wrote {args.out}: {args.out.stat().st_size:,} bytes for {len(triangles):,} triangles "
        f"({triangles.nbytes:,} bytes raw), identical bit for bit"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
