"""Presentation: HTML reports, paper figures and the paper reproduction."""
