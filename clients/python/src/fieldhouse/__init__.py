"""Python clients for the fieldhouse match server: the REST API (:class:`Client`), bots
(:class:`Bot`), the protocol's messages as dataclasses (:mod:`fieldhouse.messages`), one
exception class per error code (:mod:`fieldhouse.errors`), a local server for tests
(:class:`LocalServer`) and, with the ``env`` extra, PettingZoo and Gymnasium environments
over lock-step matches (:mod:`fieldhouse.env`).
"""

from .bot import Bot, Socket
from .errors import FieldhouseError
from .local import LocalServer
from .messages import (
    Accelerate,
    End,
    FielderPerception,
    Hello,
    MoveTo,
    Pass,
    Perception,
    PlayerPerception,
    RunTo,
    Shoot,
    Stand,
)
from .rest import Client, CreatedMatch

__all__ = [
    "Accelerate",
    "Bot",
    "Client",
    "CreatedMatch",
    "End",
    "FielderPerception",
    "FieldhouseError",
    "Hello",
    "LocalServer",
    "MoveTo",
    "Pass",
    "Perception",
    "PlayerPerception",
    "RunTo",
    "Shoot",
    "Socket",
    "Stand",
]
