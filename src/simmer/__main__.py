"""``python -m simmer`` runs the ``simmer`` command."""

from simmer.cli import main

main()
