"""The `bvhlab` command line: build, render, compare (the report's Table 1 and figures), snapshot
(raster level sheets), inspect (a node, a pixel's walk, the costliest subtrees), sweep (scenes ×
settings on Dask), animate (update policies frame by frame) and scenes.

    bvhlab build SCENE [--method M] [--bins B] [--bin-bounds box|centroids] [--axis A] [--max-leaf-size N]
                 [--sah-block N] [--optimize N [--optimize-ms MS]] [--json PATH] [--csv PATH]
    bvhlab render SCENE --out PNG [--method M] [--width W --height H] [--backend B] [--samples-per-axis N]
                  [--bvh-depth A:B] [--heatmap]
    bvhlab compare SCENE --out DIR [--methods median,mean,sah12,sah32] [--frames N]
    bvhlab snapshot SCENE --out PNG [--bvh-depth A:B | --sheet]
    bvhlab inspect SCENE [build options] --node N | --pixel X,Y | --worst K [--tree FILE] [--save-tree FILE]
                   [--json PATH]
    bvhlab animate ANIMATION --frames A-B [--policy P,Q] [--backend cpu] --out DIR
    bvhlab sweep SPEC.toml --out DIR [--scheduler tcp://HOST:PORT | --workers N] [--retry-failed]
    bvhlab scenes
"""

from __future__ import annotations

import argparse
import os
import signal
import sys

from .._atomic import WriteError
from .._core import BuildCancelled
from . import (
    animate_cmd,
    build_cmd,
    compare_cmd,
    inspect_cmd,
    options,
    render_cmd,
    scenes_cmd,
    snapshot_cmd,
    sweep_cmd,
)

COMMANDS = (build_cmd, render_cmd, compare_cmd, snapshot_cmd, inspect_cmd, sweep_cmd, animate_cmd, scenes_cmd)


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="bvhlab", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(sub)
    return p


def main(argv=None) -> int:
    """Runs one command. Bad input (a file that cannot be read or written, a wrong value) prints one
    line `bvhlab CMD: error: ...` and returns 2; Ctrl-C prints `bvhlab CMD: interrupted` and
    returns 130 (the shell's code for SIGINT); neither shows a traceback."""
    argv = sys.argv[1:] if argv is None else list(argv)
    for name in ("stdout", "stderr"):  # closed (`2>&-`): None in Python, which every print then failed on
        if getattr(sys, name) is None:
            setattr(sys, name, os.fdopen(os.open(os.devnull, os.O_WRONLY), "w"))  # no file of the user's
    try:  # its checks of paths may fail too ("File name too long") or be interrupted
        args = parser().parse_args(options.join_dash_values(argv))
    except KeyboardInterrupt:
        print("bvhlab: interrupted", file=sys.stderr)
        return 130
    except OSError as e:
        return _error(argv[0] if argv else "", e)
    try:
        code = args.run(args) or 0
        sys.stdout.flush()  # here, not at exit: a pipe's buffered output fails now if its reader left
        return code
    except BrokenPipeError:
        # the reader of the output went away (`bvhlab scenes | head -1`): quiet, as a command that
        # SIGPIPE ends ("error: [Errno 32] Broken pipe" and 2 before)
        _quiet_stdout()
        return 128 + signal.SIGPIPE
    except (OSError, ValueError, TypeError, RuntimeError, BuildCancelled) as e:
        return _error(args.command, e)
    except MemoryError as e:
        return _error(args.command, f"out of memory{': ' + str(e) if str(e) else ''} (try a smaller image or scene)")
    except KeyboardInterrupt:
        print(f"bvhlab {args.command}: interrupted", file=sys.stderr)
        return 130


def _quiet_stdout() -> None:
    """stdout to /dev/null, so that the interpreter's last flush does not fail again on the broken
    pipe ("Exception ignored ... BrokenPipeError", exit 120); nothing where stdout is no file."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # io.UnsupportedOperation is an OSError
        return
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, fd)
    os.close(null)


def _error(command: str, error) -> int:
    text = str(error)
    if (
        isinstance(error, OSError)
        and not isinstance(error, WriteError)  # already "cannot write PATH: REASON"
        and error.strerror
        and error.filename
        and not text.startswith(str(error.filename))
    ):
        text = f"{error.filename}: {error.strerror}"  # no "[Errno 21]"
    print(f"bvhlab {command}: error: {text}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
