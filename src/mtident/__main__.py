"""``python -m mtident`` runs the command line."""

from mtident.cli import main

main()
