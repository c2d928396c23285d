"""Structured linear algebra: block-tridiagonal factorisation and a lineax solver."""
