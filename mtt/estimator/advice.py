"""The estimators' advice names their Python arguments (`hold='zoh'`); on a command line
the same advice must name the options (`--hold zoh`). One table for both command lines:
mtt's, and every generated module's own, into which it is rendered."""

from __future__ import annotations

# (as the Python API writes it, as a command line writes it); the longer first
COMMAND_LINE = (
    ("offset=False, initial_state=False", "--no-offset --no-initial-state"),
    ("hold='zoh'", "--hold zoh"),
    ("hold='linear'", "--hold linear"),
    ("C='auto'", "--filter auto"),
    ("method='iv'", "--method iv"),
    ("method='pem'", "--method pem"),
    ("method='ls'", "--method ls"),
    ("noise='auto'", "--noise auto"),
    ("engine='ode'", "--engine ode"),
    ("engine='moments'", "--engine moments"),
    ("bounds=(lo, hi)", "--bounds LO:HI"),
    ("with bounds=", "with --bounds"),
    ("lower S0 (prior_weight sets one", "lower --S0 (--S0-relative sets one"),
)


def for_command_line(text: str) -> str:
    """A message of an estimator as a command line's user reads it."""
    for python, option in COMMAND_LINE:
        text = text.replace(python, option)
    return text
