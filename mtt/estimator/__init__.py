"""Theta -> a standalone estimator module (the algorithm lives in templates/)."""
