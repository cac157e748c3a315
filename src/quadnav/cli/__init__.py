"""The ``quadnav`` command line: a thin layer over the library."""
