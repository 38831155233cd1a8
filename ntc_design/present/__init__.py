"""ntc_design.present."""
