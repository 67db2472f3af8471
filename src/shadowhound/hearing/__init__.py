"""Hearing: recordings a person speaks into the dashboard, transcribed by an OpenAI-compatible
server (`speech:` in the profile), and the few spoken words that are not a mission (a stop).

No skills, no robot: the web room turns a transcript into a mission or an e-stop.
"""

from ..errors import AudioProblem, TranscriptionError
from .audio import ALLOWED, Audio, inspect, taken
from .commands import is_stop
from .transcribe import Transcriber, not_configured

__all__ = [
    "ALLOWED",
    "Audio",
    "AudioProblem",
    "Transcriber",
    "TranscriptionError",
    "inspect",
    "is_stop",
    "not_configured",
    "taken",
]
