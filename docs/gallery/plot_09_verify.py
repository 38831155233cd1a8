"""
Verifying a certificate made elsewhere
======================================

A certificate carries what it takes to prove its claims again: verify it against your own
file and θ without trusting whoever made it. A changed number fails, even with the digest
recomputed.
"""

import copy
import json
import tempfile
from pathlib import Path

import ntc_design as nd
from ntc_design.certify import certify, verify, verify_file, write_certificate

# the bundled examples, wherever the package is installed (no checkout needed)
EXAMPLES = nd.example_path()

res = certify(nd.load(EXAMPLES / "g1.yaml"), [1, 2, -1], gain="1/(1+t)")
path = Path(tempfile.mkdtemp()) / "g1.json"
write_certificate(res.certificate, path)
ver = verify_file(path, nd.load(EXAMPLES / "g1.yaml"), [1, 2, -1])
print(ver)
forged = copy.deepcopy(json.loads(path.read_text()))
forged["results"]["eig_bound"] = 100.0
print(verify(forged))
