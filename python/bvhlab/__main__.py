import sys

try:
    from .cli import main
except KeyboardInterrupt:  # Ctrl-C while the commands load (the package itself: bvhlab._as_main)
    print("bvhlab: interrupted", file=sys.stderr)
    sys.exit(130)

sys.exit(main())
