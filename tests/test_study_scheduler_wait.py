"""A study on a cluster that no worker has joined yet says so, then waits for one (it
waited without a word; `camtask render` already warned)."""

import json
import os
import threading

from testbed.cli import main


def test_a_study_waits_for_a_worker_and_says_so(capsys, monkeypatch):
    from distributed import LocalCluster

    monkeypatch.setenv("MALLOC_TRIM_THRESHOLD_", os.environ.get("MALLOC_TRIM_THRESHOLD_", "65536"))  # restored
    with LocalCluster(n_workers=0, processes=False, threads_per_worker=1, dashboard_address=None) as cluster:
        joins = threading.Timer(1.0, cluster.scale, (1,))
        joins.start()
        try:
            assert main(["study", "static", "--objects", "2", "--k", "2", "--candidates", "6", "--trials", "2",
                         "--taskers", "uniform", "--no-progress", "--json", "--scheduler",
                         cluster.scheduler_address]) == 0
        finally:
            joins.join()
    out, err = capsys.readouterr()
    assert err == (f"warning: --scheduler: no worker has joined {cluster.scheduler_address} yet; waiting for one "
                   "(Ctrl-C stops)\n")
    assert json.loads(out)["meta"]["workers"] == 1
