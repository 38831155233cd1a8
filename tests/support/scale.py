"""The proof methods a scale certificate used, per component."""


def _methods(cert):
    return cert["results"]["methods"]
