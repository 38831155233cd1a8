"""Rigorous numerics shared by every layer: exact dyadic arithmetic and verified
floating-point positive-definiteness tests (:mod:`.exact`), Arb ball arithmetic on
expressions of t (:mod:`.interval`)."""
