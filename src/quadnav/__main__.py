"""``python -m quadnav`` runs the command line."""

from quadnav.cli.launch import console

console()
