"""The `mtt` command line."""
