"""W's build by MUMPS's Schur complement (route ``schur``, ICNTL(19)) against the selected inverse on the
depth-graded sphere mesh (two bodies, ``tests/support/sphere.py``'s model; depth_growth 1.5, coarsening 2,
field_cell 0.25) at one a/h: wall and CPU time of each build after the model's own, and their largest difference.

Usage (from the repository root)::

    OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python benchmarks/bench_graded_routes.py 16
"""

import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE.parent))

from support.sphere import sphere_model  # noqa: E402

aoh = float(sys.argv[1])
body, problem, a, p0, h = sphere_model(aoh, 9.0, 1.5, flat=True, mu=0.5, depth_growth=1.5, coarsening=2,
                                       field_cell=0.25)
problem.initial_state()
d = problem.operators.delassus
H = problem.contact.H_free
print(problem.n_dofs, problem.contact.nc, "factorise", d.stats["factorize_time"], "W at set-up",
      d.stats["last_build_time"], flush=True)
ref = None
for route in ("schur", "selected_inverse"):
    c0 = time.process_time()
    W = d.build(H, method=route)
    print(route, f"wall {d.last_build_time:.1f} s, CPU {time.process_time() - c0:.1f} s",
          d.stats.get("schur_factorize_time"), flush=True)
    if route == "schur":
        d._drop_schur()  # its own factorisation: free it before the next route
    if ref is None:
        ref = W
    else:
        print("max diff", float(np.abs(W - ref).max() / np.abs(ref).max()))
