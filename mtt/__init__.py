"""mtt: from a bond graph with one unknown parameter to an estimator for that parameter."""

__version__ = "0.1.0"
