"""
Your own 5-agent network from networkx
======================================

A ``networkx.DiGraph`` whose edge u → v carries A_vu (v listens to u). Scalars are accepted
for d = 1; the topology is validated like a file.
"""

import matplotlib.pyplot as plt

import ntc_design as nd
from ntc_design.errors import optional_module
from ntc_design.interop import topology_from_networkx
from ntc_design.reports.graph_figure import topology_figure

# networkx comes with the interop extra: without it, one line says which to install
nx = optional_module("networkx", "interop", "this example")

g = nx.DiGraph()
g.add_weighted_edges_from(
    [
        ("a", "b", 2.0),
        ("b", "c", 1.0),
        ("c", "d", -0.5),
        ("d", "e", 1.0),
        ("e", "a", 1.5),
        ("a", "c", -1.0),
    ]
)
top = topology_from_networkx(g)
print(top)
des = nd.design(top, [2.0], margin=0.1)
print(des.table().text())
fig = topology_figure(des.topology, des.informed, des.B)

plt.show()  # in a notebook or a script: display the figures
