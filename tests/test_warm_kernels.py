"""tests/_warm_kernels.py, which fills numba's cache before the suite's processes start (tests/conftest.py), runs
clean: a part that broke (an API it calls changed) would leave the kernels to be compiled again in every process."""

from __future__ import annotations

from conftest import WARM_PARTS, warm_up


def test_every_part_of_the_kernel_warm_up_runs_clean(request):
    runs = warm_up(request.config)
    assert sorted(runs) == sorted(WARM_PARTS)
    for part, (rc, stderr) in runs.items():
        assert rc == 0 and not stderr.strip(), f"tests/_warm_kernels.py {part}: exit {rc}\n{stderr[-3000:]}"
