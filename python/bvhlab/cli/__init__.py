"""The `bvhlab` command line: build, render, compare (the report's Table 1 and figures),
snapshot (raster level sheets) and scenes.

    bvhlab build SCENE [--method M] [--bins B] [--axis A] [--max-leaf-size N] [--json PATH]
    bvhlab render SCENE --out PNG [--method M] [--width W --height H] [--backend B] [--samples-per-axis N]
                  [--bvh-depth A:B] [--heatmap]
    bvhlab compare SCENE --out DIR [--methods median,mean,sah12,sah32] [--frames N]
    bvhlab snapshot SCENE --out PNG [--bvh-depth A:B | --sheet]
    bvhlab scenes
"""
from __future__ import annotations

import argparse
import sys

from . import build_cmd, compare_cmd, render_cmd, scenes_cmd, snapshot_cmd

COMMANDS = (build_cmd, render_cmd, compare_cmd, snapshot_cmd, scenes_cmd)


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="bvhlab", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(sub)
    return p


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    try:
        return args.run(args) or 0
    except (FileNotFoundError, ValueError, TypeError, RuntimeError) as e:
        print(f"bvhlab {args.command}: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"bvhlab {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
