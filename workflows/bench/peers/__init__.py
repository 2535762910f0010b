"""Peers of our kernels on the same model: the scipy `solve_ivp` code a user would write
(`jeffcott_scipy`) and a plain C floor of the right-hand side (`jeffcott_c`, source beside it)."""
