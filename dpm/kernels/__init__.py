"""numba kernels: functions over arrays only (no Python objects), ``@njit(cache=True)``.

This package imports only numpy, numba, math and itself. The object layer composes a
step from these kernels through :mod:`dpm.plan`.
"""
