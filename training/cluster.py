"""The one way this project connects to Ray (``--backend ray``).

:func:`ray_session` connects to Ray, a local instance of ``workers`` CPUs or the cluster
``address`` names, unless this process is already connected; it shuts Ray down at the
end only when it connected here. So ``fetchcarry generate``'s episodes, the benchmark's
and :func:`training.reproduce.jobs.run_jobs`' each open a session, and a reproduction
opens one around its stages, which then find Ray connected: Ray starts once. Ray is an
optional extra, imported only here.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from fetchcarry_env.errors import InputError


class RayMissingError(InputError):
    """``--backend ray`` without Ray installed."""


@contextmanager
def ray_session(workers: int, address: str | None = None) -> Iterator[Any]:
    """The ``ray`` module, connected (a local instance of ``workers`` CPUs, or ``address``) while the block runs."""
    try:
        import ray  # an optional extra
    except ModuleNotFoundError:
        raise RayMissingError("the Ray backend needs Ray: pip install 'fetchcarry[ray]' (or pip install ray)") from None
    started_here = not ray.is_initialized()
    if started_here and address is None:
        ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    elif started_here:
        ray.init(address=address, include_dashboard=False, log_to_driver=False)
    try:
        yield ray
    finally:
        if started_here:
            ray.shutdown()
