"""The one place that decides how model kernels are compiled."""

from numba import njit

#: Compile a scalar physics function or a kernel: nopython, cached on disk so
#: that a warm process (or a worker of a campaign) pays no compile time.
jit = njit(cache=True, nogil=True)
