"""A local Dask cluster listens on 127.0.0.1 only, as every other socket of SimMeR: its
dashboard was started with ``dashboard_address=":0"``, which bound every interface."""

from __future__ import annotations

import pytest

from simmer.sweep import dask_engine
from simmer.sweep.engine import LOOPBACK

pytest.importorskip("distributed")
psutil = pytest.importorskip("psutil")  # installed with distributed

pytestmark = pytest.mark.timeout(300)


@pytest.mark.slow
def test_every_socket_of_a_local_cluster_is_on_loopback() -> None:
    executor = dask_engine(workers=1)()  # as `simmer sweep --engine dask` makes it
    try:
        me = psutil.Process()
        listening = [
            (process.pid, connection.laddr.ip)
            for process in (me, *me.children(recursive=True))
            for connection in process.net_connections(kind="inet")
            if connection.status == psutil.CONN_LISTEN
        ]
    finally:
        executor.shutdown()
    assert len(listening) >= 3  # the scheduler, the worker and its nanny at least
    assert {ip for _, ip in listening} == {LOOPBACK}, listening
