"""Helpers shared by the tests that came from test_figlist.py."""


def _no_certify(*a, **k):
    raise AssertionError("rendering certified")
