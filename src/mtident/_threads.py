"""One thread for the linear algebra of many tiny problems.

The model-robust fit solves thousands of systems of a few unknowns and runs L-BFGS-B on a few
variables. OpenBLAS threads on such sizes only wait on one another, and where the other cores
are busy (a test suite's workers, a benchmark's shards, a monitor beside other programs) each
wait lasts a time slice: a call of L-BFGS-B then took a hundred times as long.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache

from threadpoolctl import ThreadpoolController

__all__ = ["one_blas_thread"]


@cache
def _controller() -> ThreadpoolController:
    # made at first use, once numpy's and scipy's BLAS libraries are loaded
    return ThreadpoolController()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Limit every loaded BLAS library to one thread inside the block (restored after it).

    Yields
    ------
    None

    Examples
    --------
    >>> import numpy as np
    >>> with one_blas_thread():
    ...     float(np.linalg.solve(np.eye(2), np.ones(2))[0])
    1.0
    """
    with _controller().limit(limits=1, user_api="blas"):
        yield
