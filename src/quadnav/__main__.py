"""``python -m quadnav`` runs the command line."""

import sys

from quadnav.cli.launch import main

sys.exit(main())
