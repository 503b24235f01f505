"""Presentation: how mtt's results read and look, for the command line and the API alike.

Text, LaTeX and JSON of the derived representations (report), the bond graph drawn
(drawing), the figures of an experiment (plots) and Bode diagrams (bode).
"""
