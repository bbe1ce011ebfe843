"""The command line: the composition root. Only this package decides how output looks."""

ERROR_PREFIX = "bt-grasp: error: "  # the one error format of every command: ``bt-grasp: error: <one sentence>``
