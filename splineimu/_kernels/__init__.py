"""Private numba kernels: contiguous float64 arrays in, preallocated outputs last, no checks.

Public modules validate and allocate, then call these. Nothing here imports a public module.
"""
