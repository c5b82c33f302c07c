"""The digest of a run's weights by their content, so that the same weights give the same digest.

``model.pt``'s bytes are not reproducible: the archive ``torch.save`` writes names its
inner folder after the temporary file it was saved to (a random name), so one run
trained twice to bit-identical tensors gives two different file hashes.
:func:`weights_digest` hashes what was saved instead: every entry's key, dtype, shape and
bytes, in order (nested dicts and lists walked; other values by their ``repr``).
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

CONTENT_PREFIX = "tensors:"  # a content digest, told apart from the file hashes folders made before it hold


def weights_digest(model: Path) -> str:
    """``tensors:`` and the sha256 of the weights saved in ``model`` (a ``model.pt``), by content."""
    import torch  # heavy: only when a digest is asked for

    digest = hashlib.sha256()
    _feed(digest, torch.load(model, map_location="cpu", weights_only=True), torch)
    return CONTENT_PREFIX + digest.hexdigest()


def file_digest(model: Path) -> str:
    """The sha256 of ``model``'s bytes: what a folder's ``weights.json`` held before content digests."""
    return hashlib.sha256(model.read_bytes()).hexdigest()


def same_weights(model: Path, recorded: Any) -> bool:
    """Whether ``model`` holds the weights ``recorded`` names (a content digest, or an older file hash)."""
    if not isinstance(recorded, str):
        return False
    if recorded.startswith(CONTENT_PREFIX):
        return weights_digest(model) == recorded
    return file_digest(model) == recorded


def _feed(digest: Any, value: Any, torch: Any) -> None:
    if isinstance(value, torch.Tensor):
        tensor = value.detach().cpu().contiguous()
        digest.update(f"tensor {tensor.dtype} {tuple(tensor.shape)};".encode())
        digest.update(tensor.view(torch.uint8).numpy().tobytes() if tensor.numel() else b"")
    elif isinstance(value, dict):
        digest.update(f"dict {len(value)};".encode())
        for key, item in value.items():
            digest.update(f"key {key!r};".encode())
            _feed(digest, item, torch)
    elif isinstance(value, list | tuple):
        digest.update(f"list {len(value)};".encode())
        for item in value:
            _feed(digest, item, torch)
    else:
        digest.update(f"value {value!r};".encode())
