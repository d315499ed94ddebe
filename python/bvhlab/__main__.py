import sys

try:
    from .cli import main
except KeyboardInterrupt:  # Ctrl-C while numpy and the core load: no traceback either
    sys.exit(130)

sys.exit(main())
