"""BLAS threads during a fit (``docs/fitting.md``, "Speed").

The matrices of a fit are N x p with p <= ~15 (Jacobian products, a thin SVD per
trust-region step): memory-bound work that BLAS threads do not speed up, while on a busy machine
their spin-waiting makes each of ``least_squares``' small BLAS calls take milliseconds (measured:
a 13k-sample TR75 fit spent 3x longer in SciPy's trust-region step than in the model).
:func:`single_thread_blas` limits every BLAS loaded in the process (OpenBLAS, MKL, BLIS) to one
thread with ``threadpoolctl`` and restores the previous limits afterwards.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["single_thread_blas"]


@contextmanager
def single_thread_blas() -> Iterator[None]:
    """Run a block with BLAS limited to one thread (``threadpoolctl.threadpool_limits``).

    Examples
    --------
    >>> with single_thread_blas():
    ...     pass
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        yield
