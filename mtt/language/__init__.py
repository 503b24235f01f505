"""The .bg language: text -> parse tree -> validated bond graph, with located diagnostics."""
