"""ntc_design.numerics."""
