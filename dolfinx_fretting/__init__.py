"""dolfinx_fretting: fretting wear simulation with DOLFINx.

Frictional contact is solved on the Delassus (compliance) operator W = H K^-1 H^T by the Uzawa iteration
with De Saxce's bipotential projection onto the Coulomb cone; the Archard law updates the wear gap.
"""

__version__ = "0.1.0"
