"""Review of hunts 45a-c: what their fixes left wrong (each test failed before its fix)."""
import numpy as np
import pytest

import graybox as gb


# -- simulate: a frame of the default input names is read by them in any column order ------------------------------
def test_a_frame_of_the_default_names_in_another_order_still_feeds_a_structure_using_some_of_them():
    import pandas as pd

    # 62ed8d8 kept the default names' reading only for the columns in the order u1, u2: a frame of columns u2, u1
    # (read by name before 440cdd0) was refused as naming 'only some of the inputs ['u2']'
    rng = np.random.default_rng(0)
    u = rng.uniform(size=(10, 2))
    st, th = ["y(k-1)", "u2(k-1)"], [0.5, 1.0]
    want = gb.simulate(st, th, u, [0.0])
    assert np.array_equal(gb.simulate(st, th, pd.DataFrame({"u2": u[:, 1], "u1": u[:, 0]}), [0.0]), want)
    st1 = ["y(k-1)", "u1(k-1)"]
    assert np.array_equal(gb.simulate(st1, th, pd.DataFrame({"u2": u[:, 1], "u1": u[:, 0]}), [0.0]),
                          gb.simulate(st1, th, u, [0.0]))
