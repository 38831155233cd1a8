"""ntc_design.gain."""
