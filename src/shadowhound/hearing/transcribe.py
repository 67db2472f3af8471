"""The transcription client: a recording to text through an OpenAI-compatible
`POST /v1/audio/transcriptions` (OpenAI's whisper-1 or gpt-4o-mini-transcribe, speaches /
faster-whisper-server, vLLM serving a Whisper model), set in the profile's `speech:` section.

The recording is sent as multipart form data (`file`, `model`, optional `language`,
`response_format=json`) and never kept; the answer's `text` is the transcript. A server that
does not answer, answers with an error or with something that is not a transcript gets a
`TranscriptionError` that says which and what to check.
"""

from __future__ import annotations

import json
import os
import urllib.error
import urllib.request
import uuid
from typing import Any

from ..config import SpeechConfig
from ..errors import TranscriptionError
from .audio import Audio

PATH = "/audio/transcriptions"


def not_configured(config: SpeechConfig) -> str:
    """Why there is no transcription ("" when there is): what to set."""
    if config.base_url.strip():
        return ""
    return (
        "no transcription server is configured: set speech.base_url in the profile (or "
        "SHADOWHOUND_SPEECH__BASE_URL) to an OpenAI-compatible server, e.g. "
        "https://api.openai.com/v1 with speech.model whisper-1, or a local speaches / "
        "faster-whisper-server at http://127.0.0.1:8000/v1 (docs/web.md)"
    )


class Transcriber:
    """Sends recordings to the configured server, one request each."""

    def __init__(self, config: SpeechConfig, environ: dict[str, str] | None = None) -> None:
        self.config = config
        env = os.environ if environ is None else environ
        self._key = env.get(config.api_key_env, "") if config.api_key_env else ""

    @property
    def url(self) -> str:
        return self.config.base_url.rstrip("/") + PATH

    def transcribe(self, data: bytes, audio: Audio) -> str:
        """The transcript of `data` (whitespace trimmed; may be empty: nothing was heard)."""
        why = not_configured(self.config)
        if why:
            raise TranscriptionError(why, 503)
        fields = {"model": self.config.model, "response_format": "json"}
        if self.config.language:
            fields["language"] = self.config.language
        boundary = uuid.uuid4().hex
        body = _multipart(boundary, fields, audio, data)
        headers = {"Content-Type": f"multipart/form-data; boundary={boundary}"}
        if self._key:
            headers["Authorization"] = f"Bearer {self._key}"
        request = urllib.request.Request(self.url, data=body, headers=headers, method="POST")
        try:
            with urllib.request.urlopen(request, timeout=self.config.timeout) as response:
                raw = response.read(1_000_000)
        except urllib.error.HTTPError as exc:
            detail = exc.read(500).decode("utf-8", "replace").strip()
            raise TranscriptionError(
                f"the transcription server at {self.url} answered HTTP {exc.code}"
                + (f": {detail}" if detail else "")
                + (" (check speech.api_key_env)" if exc.code in (401, 403) else "")
            ) from exc
        except (urllib.error.URLError, TimeoutError, OSError) as exc:
            reason = getattr(exc, "reason", exc)
            raise TranscriptionError(
                f"the transcription server at {self.url} did not answer ({reason}): start it "
                "or fix speech.base_url",
                503,
            ) from exc
        return _text(raw, self.url)


def _text(raw: bytes, url: str) -> str:
    try:
        answer: Any = json.loads(raw)
    except ValueError:
        answer = None
    if not isinstance(answer, dict) or not isinstance(answer.get("text"), str):
        shown = raw[:120].decode("utf-8", "replace")
        raise TranscriptionError(
            f"the transcription server at {url} did not answer with a transcript "
            f'({{"text": ...}} expected, got {shown!r})'
        )
    return " ".join(answer["text"].split())


def _multipart(boundary: str, fields: dict[str, str], audio: Audio, data: bytes) -> bytes:
    parts = []
    for name, value in fields.items():
        head = f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"\r\n\r\n'
        parts.append(f"{head}{value}\r\n".encode())
    parts.append(
        (
            f'--{boundary}\r\nContent-Disposition: form-data; name="file"; '
            f'filename="{audio.filename}"\r\nContent-Type: {audio.content_type}\r\n\r\n'
        ).encode()
        + data
        + b"\r\n"
    )
    parts.append(f"--{boundary}--\r\n".encode())
    return b"".join(parts)
