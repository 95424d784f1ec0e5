"""Review 47e: regressions found in the changes merged this session."""

import logging
import threading
import time

from test_grid_executors import _death_cells


def test_a_client_whose_cluster_has_no_worker_yet_is_waited_for_not_ended():
    """An adaptive cluster starts its workers once tasks arrive (from a batch queue, after minutes): a run on its
    client has had no worker *yet*, none *left*, and the watch of 99a34d7 ended it after worker_timeout with
    'no worker ... (all gone, none restarted)' before the first worker came."""
    from distributed import Client, LocalCluster

    from graybox.experiments._executors import DaskCluster

    cluster = LocalCluster(n_workers=0, threads_per_worker=1, processes=True, dashboard_address=":0",
                           silence_logs=logging.ERROR)
    with cluster, Client(cluster) as client:
        cells, data = _death_cells(("LS",))
        late = threading.Timer(3.0, lambda: cluster.scale(1))  # the first worker, after 3 worker_timeouts
        late.start()
        try:
            rows = list(DaskCluster(client=client, worker_timeout=1).run(cells, data))
        finally:
            late.join()
    assert [r["status"] for r in rows] == ["ok"]
