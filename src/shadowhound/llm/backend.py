"""LLMBackend: the official `openai` client against any OpenAI-compatible server.

Every failure becomes a BackendError whose message names the URL, the model and what to do.
Retries (`max_retries`, exponential backoff, honouring the server's Retry-After) are done here,
not by the openai client, so that a cancelled mission stops them: a request made with a
`cancelled` event runs on its own thread, and when the event is set the caller stops waiting at
once, the request is abandoned (its thread ends when the server answers or `llm.timeout`
passes) and no further attempt is sent.
"""

from __future__ import annotations

import email.utils
import json
import logging
import math
import os
import random
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ..config import LLMConfig
from ..errors import BackendCancelled, BackendError, BackendUnavailable
from ..plan import Usage

log = logging.getLogger(__name__)

_CANCEL_POLL = 0.02  # seconds between looks at the cancel event while a request is in flight
_FIRST_BACKOFF, _MAX_BACKOFF = 0.5, 8.0  # seconds, as the openai client's own retries
_MAX_RETRY_AFTER = 60.0  # a server asking for a longer wait is not retried
_ABANDONED = object()  # what an attempt returns when the caller stopped waiting


@dataclass
class Completion:
    """One chat completion: the assistant message (as a plain dict) and what it cost."""

    message: dict[str, Any]
    usage: Usage
    finish_reason: str | None = None
    raw_usage: bool = True  # False when the server reported no usage and tokens were estimated
    seconds: float = 0.0


def estimate_tokens(payload: Any) -> int:
    """Rough token count (about 4 characters a token) for servers that report no usage."""
    text = payload if isinstance(payload, str) else json.dumps(payload, separators=(",", ":"))
    return max(1, math.ceil(len(text) / 4))


def request_hints(backend: str) -> dict[str, Any]:
    """Extra request fields that let the server reuse its prompt cache.

    llama.cpp's server keeps the evaluated prompt and reuses the longest common prefix only
    when asked (`cache_prompt`; llama-cpp-python reuses it anyway and ignores the field).
    OpenAI and vLLM cache shared prefixes by themselves.
    """
    return {"cache_prompt": True} if backend == "llamacpp" else {}


@dataclass
class LLMBackend:
    """A chat-completions client for one server and model."""

    backend: str
    config: LLMConfig
    _client: Any = field(default=None, repr=False)

    @property
    def where(self) -> str:
        return f"{self.config.base_url or '(no base_url)'} (model {self.config.model or '?'})"

    def api_key(self) -> str:
        name = self.config.api_key_env
        key = os.environ.get(name, "") if name else ""
        if not key and self.backend == "openai" and "api.openai.com" in self.config.base_url:
            raise BackendUnavailable(
                f"no API key for {self.where}: set the environment variable {name}"
            )
        return key or "not-needed"  # local servers accept any key

    def client(self) -> Any:
        if self._client is None:
            if not self.config.base_url or not self.config.model:
                raise BackendUnavailable(
                    f"backend {self.backend!r} needs llm.base_url and llm.model "
                    "(profile, SHADOWHOUND_LLM__BASE_URL / __MODEL, or --base-url / --model)"
                )
            try:
                from openai import OpenAI
            except ImportError as exc:
                raise BackendUnavailable(
                    "language-model backends need the 'llm' extra: pip install 'shadowhound[llm]'"
                ) from exc
            self._client = OpenAI(
                base_url=self.config.base_url,
                api_key=self.api_key(),
                timeout=self.config.timeout,
                max_retries=0,  # retried in `_call`, where a cancel can stop them
            )
        return self._client

    def complete(
        self,
        messages: list[dict[str, Any]],
        *,
        cancelled: threading.Event | None = None,
        **options: Any,
    ) -> Completion:
        """One chat completion. Raises BackendError (never an openai exception).

        With `cancelled`, setting the event ends the wait at once with BackendCancelled.
        """
        request: dict[str, Any] = {
            "model": self.config.model,
            "messages": messages,
            "temperature": self.config.temperature,
            "max_tokens": self.config.max_tokens,
            **{k: v for k, v in options.items() if v is not None},
        }
        started = time.perf_counter()
        response = self._call(lambda client: client.chat.completions.create(**request), cancelled)
        seconds = time.perf_counter() - started
        choices = getattr(response, "choices", None) or []
        if not choices or getattr(choices[0], "message", None) is None:
            raise BackendError(f"the language model at {self.where} returned no message")
        message = choices[0].message.model_dump(exclude_none=True)
        usage = getattr(response, "usage", None)
        if usage is not None and getattr(usage, "prompt_tokens", None) is not None:
            cost = Usage(usage.prompt_tokens or 0, usage.completion_tokens or 0, 1)
            reported = True
        else:
            prompt = estimate_tokens(messages) + estimate_tokens(options.get("tools") or "")
            cost = Usage(prompt, estimate_tokens(message), 1, estimated=True)
            reported = False
        return Completion(message, cost, choices[0].finish_reason, reported, seconds)

    def embed(self, model: str, texts: list[str]) -> Any:
        """The server's embeddings response for `texts`. Raises BackendError."""
        return self._call(lambda client: client.embeddings.create(model=model, input=texts), None)

    # -- requests, retries and cancellation ----------------------------------------------------

    def _call(self, request: Callable[[Any], Any], cancelled: threading.Event | None) -> Any:
        """`request(client)` with up to `max_retries` retries; openai errors become
        BackendError. Nothing is sent once `cancelled` is set."""
        import openai

        client = self.client()
        for attempt in range(self.config.max_retries + 1):
            if cancelled is not None and cancelled.is_set():
                raise self._cancelled()
            try:
                response = _attempt(request, client, cancelled)
            except (openai.OpenAIError, ValueError) as exc:
                wait = _retry_delay(exc, attempt) if attempt < self.config.max_retries else None
                if wait is None:
                    raise self._explain(exc) from exc
                log.info(
                    "the language model at %s failed (%s); retrying in %.2f s",
                    self.where,
                    type(exc).__name__,
                    wait,
                )
                if (cancelled or threading.Event()).wait(wait):  # a plain sleep without one
                    raise self._cancelled() from exc
                continue
            if response is _ABANDONED:
                raise self._cancelled()
            return response
        raise AssertionError("unreachable: the last attempt returns or raises")

    def _cancelled(self) -> BackendCancelled:
        return BackendCancelled(
            f"the request to the language model at {self.where} was "
            "abandoned: the mission was cancelled"
        )

    def _explain(self, exc: Exception) -> BackendError:
        import openai

        if isinstance(exc, openai.APITimeoutError):
            return BackendError(
                f"the language model at {self.where} did not answer within "
                f"{self.config.timeout:g} s (llm.timeout); is the server overloaded?"
            )
        if isinstance(exc, openai.APIConnectionError):
            return BackendError(
                f"cannot reach the language model at {self.where}: {exc.__cause__ or exc}; "
                "is the server running and the URL right?"
            )
        if isinstance(exc, openai.APIStatusError):
            return BackendError(
                f"the language model at {self.where} answered HTTP {exc.status_code}: "
                f"{_error_text(exc)}",
                exc.status_code,
            )
        if isinstance(exc, openai.OpenAIError):
            return BackendError(f"the language model at {self.where} failed: {exc}")
        # The client lets a malformed JSON body escape as a ValueError.
        return BackendError(
            f"the language model at {self.where} answered something that is "
            f"not a chat completion: {exc}"
        )

    # -- start-up check ------------------------------------------------------------------------

    def check(self) -> list[str]:
        """Check that the server answers and has the model. Returns what was verified.

        Raises BackendUnavailable naming the URL, the model and how to fix it.
        """
        cfg = self.config
        self.client()  # validates base_url, model, the extra and the key
        done = []
        if self.backend == "ollama":
            root = cfg.base_url.rstrip("/").removesuffix("/v1")
            tags = self._get_json(f"{root}/api/tags").get("models", [])
            names = [m.get("name", "") for m in tags if isinstance(m, dict)]
            done.append(f"Ollama at {root} answers ({len(names)} models)")
            if not _has_model(cfg.model, names):
                raise BackendUnavailable(
                    f"Ollama at {root} does not have the model {cfg.model!r} (it has: "
                    f"{', '.join(names) or 'none'}); run: ollama pull {cfg.model}"
                )
        else:
            listed = self._get_json(cfg.base_url.rstrip("/") + "/models")
            names = [m.get("id", "") for m in listed.get("data", []) if isinstance(m, dict)]
            done.append(f"{cfg.base_url} answers ({len(names)} models)")
            if names and not _has_model(cfg.model, names):
                raise BackendUnavailable(
                    f"the server at {cfg.base_url} does not serve the model {cfg.model!r} "
                    f"(it serves: {', '.join(names[:20])}); set llm.model or --model to one "
                    "of them"
                )
        done.append(f"model {cfg.model!r} is available")
        return done

    def _get_json(self, url: str) -> dict[str, Any]:
        request = urllib.request.Request(url, headers={"Authorization": f"Bearer {self.api_key()}"})
        try:
            with urllib.request.urlopen(request, timeout=self.config.timeout) as response:
                data = json.loads(response.read().decode("utf-8"))
        except urllib.error.HTTPError as exc:
            raise BackendUnavailable(
                f"{url} answered HTTP {exc.code}; check llm.base_url for backend "
                f"{self.backend!r} (model {self.config.model!r}) and the API key"
            ) from exc
        except (urllib.error.URLError, TimeoutError, OSError) as exc:
            reason = getattr(exc, "reason", exc)
            raise BackendUnavailable(
                f"cannot reach {url} ({reason}) within {self.config.timeout:g} s: start the "
                f"{self.backend} server or fix llm.base_url (model {self.config.model!r})"
            ) from exc
        except ValueError as exc:
            raise BackendUnavailable(
                f"{url} did not answer JSON: is it an OpenAI-compatible server? ({exc})"
            ) from exc
        if not isinstance(data, dict):
            raise BackendUnavailable(f"{url} answered {type(data).__name__}, not a JSON object")
        return data


def _attempt(request: Callable[[Any], Any], client: Any, cancelled: threading.Event | None) -> Any:
    """One request. With a cancel event it runs on its own thread and _ABANDONED is returned as
    soon as the event is set; the abandoned thread ends by itself and its outcome is dropped."""
    if cancelled is None:
        return request(client)
    outcome: dict[str, Any] = {}
    done = threading.Event()

    def run() -> None:
        try:
            outcome["value"] = request(client)
        except BaseException as exc:  # handed to the waiting caller, or dropped if abandoned
            outcome["error"] = exc
        finally:
            done.set()

    threading.Thread(target=run, name="shadowhound-llm-request", daemon=True).start()
    while not done.wait(_CANCEL_POLL):
        if cancelled.is_set():
            log.info("abandoning a language-model request: the mission was cancelled")
            return _ABANDONED
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


def _retry_delay(exc: Exception, attempt: int) -> float | None:
    """Seconds to wait before retrying after `exc`, or None when it is not worth retrying.

    The openai client's own policy: time-outs, lost connections, 408/409/429/5xx (or what the
    server's x-should-retry says); the server's Retry-After first, else exponential backoff.
    """
    import openai

    if isinstance(exc, openai.APIStatusError):
        headers = exc.response.headers
        should = headers.get("x-should-retry")
        code = exc.status_code
        if should == "false" or (should != "true" and code not in (408, 409, 429) and code < 500):
            return None
        after = _retry_after(headers)
        if after is not None:
            return after if after <= _MAX_RETRY_AFTER else None
    elif not isinstance(exc, openai.APIConnectionError):  # includes time-outs
        return None
    return min(_FIRST_BACKOFF * 2.0**attempt, _MAX_BACKOFF) * (1 - 0.25 * random.random())


def _retry_after(headers: Any) -> float | None:
    """The server's Retry-After (retry-after-ms, or seconds, or an HTTP date) if positive."""
    in_ms, given = headers.get("retry-after-ms"), headers.get("retry-after")
    seconds: float | None = None
    try:
        if in_ms:
            seconds = float(in_ms) / 1000
        elif given:
            try:
                seconds = float(given)
            except ValueError:
                seconds = email.utils.parsedate_to_datetime(given).timestamp() - time.time()
    except (TypeError, ValueError):  # not a number nor a date: fall back to our backoff
        return None
    return seconds if seconds is not None and math.isfinite(seconds) and seconds > 0 else None


def _has_model(model: str, names: list[str]) -> bool:
    tagged = model if ":" in model else f"{model}:latest"
    return model in names or tagged in names


def _error_text(exc: Any) -> str:
    body = getattr(exc, "body", None)
    if isinstance(body, dict):
        err = body.get("error", body)
        if isinstance(err, dict) and err.get("message"):
            return str(err["message"])[:500]
        return json.dumps(body)[:500]
    return str(exc)[:500]
