"""The command line: the composition root. Only this package decides how output looks."""
