"""ntc_design.io."""
