"""``python -m quadnav`` runs the command line."""

import sys

from quadnav.cli.main import main

sys.exit(main())
