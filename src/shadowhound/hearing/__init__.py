"""Hearing: recordings a person speaks into the dashboard, transcribed by an OpenAI-compatible
server (`speech:` in the profile), and the spoken words that are not a mission (a stop).

No skills, no robot: the web room turns a transcript into a mission or an e-stop. Reading a
recording (audio.py and its readers) is linear in its bytes and trusts no header alone; slow
work runs on `Lanes` of its own (lanes.py), short recordings first.
"""

from ..errors import AudioProblem, HearingBusy, RecordingTooLong, TranscriptionError
from .audio import ALLOWED, Audio, inspect, taken
from .commands import is_stop
from .lanes import Lanes
from .transcribe import Transcriber, not_configured

__all__ = [
    "ALLOWED",
    "Audio",
    "AudioProblem",
    "HearingBusy",
    "Lanes",
    "RecordingTooLong",
    "Transcriber",
    "TranscriptionError",
    "inspect",
    "is_stop",
    "not_configured",
    "taken",
]
