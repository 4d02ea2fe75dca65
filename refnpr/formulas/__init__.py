"""refnpr.formulas."""
