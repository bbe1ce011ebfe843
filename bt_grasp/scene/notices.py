"""Things the scene loader tells a user about their objects (a texture image missing, an object the gripper can
never pick): warnings, each said once per process. A pick bench loads its scene once per episode; the user needs
the sentence once, not once a seed. The set of sentences said is this module's only state
(:func:`forget_notices` clears it, for tests)."""

from __future__ import annotations

import logging

_said: set[str] = set()


def notice(logger: logging.Logger, sentence: str) -> None:
    """Log ``sentence`` as a warning on ``logger``, unless this process has said it already."""
    if sentence in _said:
        return
    _said.add(sentence)
    logger.warning("%s", sentence)


def forget_notices() -> None:
    _said.clear()
