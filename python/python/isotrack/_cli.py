"""The ``isotrack`` command installed with the package: the command line of the Rust binary,
run in the package's native module (one build gives the library and the command)."""

import signal
import sys


def main() -> None:
    """Runs ``isotrack ARGS...`` and exits with its exit code (README, "Exit codes")."""
    # Ctrl-C ends the command at once, as it ends the binary (Python's handler would only set a
    # flag that the engine never looks at from here).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    from . import _native

    sys.exit(_native.cli_main(["isotrack", *sys.argv[1:]]))


if __name__ == "__main__":
    main()
