"""The ``implicit-psdr`` command, installed by ``pip install .`` as a console script.

It runs the command-line tool compiled into the package's native module, the same code as the Rust
binary ``cargo install --path .`` installs: same commands, flags, outputs, messages and exit codes.
"""

import signal
import sys

from ._native import cli


def main(argv=None):
    """Runs ``implicit-psdr`` with ``argv`` (default: ``sys.argv[1:]``) and exits with its code."""
    # The tool runs outside the interpreter's loop, where Python's own Ctrl-C handler would never
    # run: let Ctrl-C end the process, as it ends the Rust binary.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    args = sys.argv[1:] if argv is None else list(argv)
    sys.exit(cli(["implicit-psdr", *args]))


if __name__ == "__main__":
    main()
