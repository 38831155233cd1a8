"""Helpers shared by the tests that came from test_scale.py."""


def _methods(cert):
    return cert["results"]["methods"]
