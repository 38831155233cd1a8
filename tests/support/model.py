"""Hypothesis strategies for network seeds."""

from hypothesis import strategies as st

seeds = st.integers(min_value=0, max_value=2**32 - 1)
