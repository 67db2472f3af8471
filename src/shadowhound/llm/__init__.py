"""Language-model backends: one OpenAI-compatible client for OpenAI, Ollama, vLLM, llama.cpp.

Needs the `llm` extra (`pip install shadowhound[llm]`); nothing here is imported by
`import shadowhound`.
"""

from __future__ import annotations

from ..errors import BackendError, BackendUnavailable
from .backend import Completion, LLMBackend

__all__ = ["BackendError", "BackendUnavailable", "Completion", "LLMBackend"]
