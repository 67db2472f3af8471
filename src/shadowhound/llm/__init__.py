"""Language-model backends: one OpenAI-compatible client for OpenAI, Ollama, vLLM, llama.cpp.

Needs the `llm` extra (`pip install shadowhound[llm]`); nothing here is imported by
`import shadowhound`.
"""

from __future__ import annotations

from .backend import BackendError, BackendUnavailable, Completion, LLMBackend

__all__ = ["BackendError", "BackendUnavailable", "Completion", "LLMBackend"]
