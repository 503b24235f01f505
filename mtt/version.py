"""mtt's version, in one place: the package, its command line and the modules it generates
(stamped in their header) read it here."""

__version__ = "0.1.0"
