"""ntc_design.certify.robust."""
