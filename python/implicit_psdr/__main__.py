"""``python -m implicit_psdr ...`` runs the ``implicit-psdr`` command-line tool."""

from .cli import main

main()
