"""Keep numpy's OpenBLAS to the calling thread while the batch works.

The batch parallelises over processes; OpenBLAS's own threads would then compete with
them for the cores (and spin while they wait). ``one_blas_thread()`` sets OpenBLAS's
thread count for the calling thread to 1 (``openblas_set_num_threads_local``, OpenBLAS
>= 0.3.27, as bundled with numpy's wheels) and restores it after. Where numpy uses
another BLAS, or that function is missing, it does nothing.
"""

from __future__ import annotations

import ctypes
import glob
import os
from contextlib import contextmanager
from functools import lru_cache

import numpy as np


@lru_cache(maxsize=1)
def _set_local():
    libs = os.path.join(os.path.dirname(os.path.dirname(np.__file__)), 'numpy.libs')
    for path in sorted(glob.glob(os.path.join(libs, '*openblas*.so*'))):
        try:
            lib = ctypes.CDLL(path)
            fn = lib.openblas_set_num_threads_local
        except (OSError, AttributeError):
            continue
        fn.argtypes, fn.restype = [ctypes.c_int], ctypes.c_int
        return fn
    return None


@contextmanager
def one_blas_thread():
    """Run the block with OpenBLAS single-threaded in this thread (module docstring)."""
    fn = _set_local()
    if fn is None:
        yield
        return
    previous = fn(1)
    try:
        yield
    finally:
        fn(previous)
