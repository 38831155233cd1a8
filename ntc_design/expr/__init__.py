"""ntc_design.expr."""
