"""A campaign on a real Dask cluster gives the local executor's results: the same runs,
seeds and counts exactly, the floats to 1e-12 (:func:`agreement.assert_same_outcome` says
why not bit for bit).

The test starts its own ``LocalCluster`` (two worker processes, one thread each) and
reaches it by address, as ``emaphm campaign --scheduler tcp://HOST:PORT`` does.
"""

from __future__ import annotations

import re
import shutil
import socket
import threading

import pytest
from support import assert_same_outcome, outcomes

distributed = pytest.importorskip("distributed")

from emaphm.campaign import (CampaignStore, DaskExecutor, SerialExecutor, paper_spec,  # noqa: E402
                             run_campaign)
from emaphm.campaign.executors import parse_scheduler_address  # noqa: E402
from emaphm.campaign.spec import parse_algorithms, parse_scenarios  # noqa: E402
from emaphm.cli import main  # noqa: E402


def spec():
    return paper_spec(runs=2, master_seed=99, budget=600, name="dask",
                      scenarios=parse_scenarios("backlash-high,short-circuit-low"),
                      algorithms=parse_algorithms("pso,gwo"))


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=40) as c:
        yield c


def test_dask_cluster_gives_the_local_results(tmp_path, cluster):
    local = tmp_path / "local.sqlite"
    remote = tmp_path / "dask.sqlite"
    a = run_campaign(spec(), local, SerialExecutor())
    b = run_campaign(spec(), remote, DaskExecutor(cluster.scheduler_address))
    assert a.finished and b.finished and b.completed == 8 and b.failed == 0
    got, want = outcomes(remote), outcomes(local)
    assert got.keys() == want.keys() and len(got) == 8
    for key in want:
        assert_same_outcome(got[key], want[key], key)
    with CampaignStore.open(remote, readonly=True) as st:
        workers = {r.worker for r in st.results()}
    assert len(workers) == 2, "both workers should have taken runs"


def test_cli_scheduler_option_and_a_client_object(tmp_path, cluster, capsys):
    store = tmp_path / "cli.sqlite"
    rc = main(["campaign", "--scenarios", "gain-low", "--algorithms", "pso", "--runs", "1",
               "--budget", "300", "--store", str(store), "--scheduler", cluster.scheduler_address,
               "--quiet"])
    assert rc == 0, capsys.readouterr().err
    # a Client given by the caller is used and left open
    with distributed.Client(cluster) as client:
        s = paper_spec(runs=2, master_seed=0, budget=300, scenarios=parse_scenarios("gain-low"),
                       algorithms=parse_algorithms("pso"))
        summary = run_campaign(s, store.with_name("client.sqlite"), DaskExecutor(client))
        assert summary.completed == 2 and client.status == "running"
    assert outcomes(store)["gain-low/pso/0"] != {}


# ----------------------------------------------------------------------------- bad addresses
@pytest.mark.parametrize("text, want", [
    ("tcp://10.0.0.1:8786", "tcp://10.0.0.1:8786"),
    ("10.0.0.1:8786", "tcp://10.0.0.1:8786"),
    ("TLS://sched.example.org:8786", "tls://sched.example.org:8786"),
    ("tcp://[::1]:8786", "tcp://[::1]:8786"),
])
def test_scheduler_addresses_are_normalised(text, want):
    assert parse_scheduler_address(text) == want


@pytest.mark.parametrize("text, words", [
    ("inproc://x", "scheme inproc:// is not supported (an inproc:// address names a scheduler "
                   "inside one Python process"),
    ("ucx://10.0.0.1:8786", "scheme ucx:// is not supported; give tcp://HOST:PORT or tls://"),
    ("tcp://10.0.0.1", "is not HOST:PORT after tcp://"),
    ("tcp://10.0.0.1:99999", "port 99999 is outside 1-65535"),
    ("tcp://host:80/path", "is not HOST:PORT"),
    ("", "the scheduler address is empty"),
])
def test_bad_scheduler_addresses_are_refused_with_the_reason(text, words):
    with pytest.raises(ValueError, match=re.escape(words)):
        parse_scheduler_address(text)


class _NotDask:
    """A TCP service on localhost that is no Dask scheduler: it closes each connection at
    once, sends garbage, or says nothing."""

    def __init__(self, mode: str) -> None:
        self.mode = mode
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.held: list[socket.socket] = []
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            if self.mode == "close":
                conn.close()
            elif self.mode == "garbage":
                conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 5\r\n\r\nhello" * 20)
                conn.close()
            else:                                 # silent: keep it open, answer nothing
                self.held.append(conn)

    def close(self) -> None:
        self.sock.close()
        for c in self.held:
            c.close()


@pytest.mark.parametrize("mode, words", [
    ("close", "did not answer as a Dask scheduler"),
    ("garbage", "did not answer as a Dask scheduler (it sent bytes that are no Dask message"),
    ("silent", "accepted the connection but gave no Dask answer within 1 s"),
])
def test_a_service_that_is_no_dask_scheduler_is_a_clear_exit_2(tmp_path, capsys, mode, words):
    server = _NotDask(mode)
    store = tmp_path / "store.sqlite"
    try:
        rc = main(["campaign", "--scenarios", "gain-low", "--algorithms", "pso", "--runs", "1",
                   "--store", str(store), "--scheduler", server.address,
                   "--connect-timeout", "1"])
    finally:
        server.close()
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert words in err and server.address in err
    assert not store.exists(), "nothing is written before the scheduler answers"


def test_nothing_listening_is_cannot_reach(tmp_path, capsys):
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()                                   # bound, never listened: refused
    rc = main(["campaign", "--store", str(tmp_path / "x.sqlite"),
               "--scheduler", f"127.0.0.1:{port}", "--connect-timeout", "1"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1
    assert f"cannot reach a Dask scheduler at tcp://127.0.0.1:{port} (Connection refused)" in err


def test_tls_without_certificates_says_where_they_go(tmp_path, capsys):
    rc = main(["campaign", "--store", str(tmp_path / "x.sqlite"),
               "--scheduler", "tls://127.0.0.1:8786", "--connect-timeout", "1"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1
    assert "tls:// needs the certificates in Dask's configuration (distributed.comm.tls.ca-file" in err


@pytest.mark.skipif(shutil.which("openssl") is None, reason="needs openssl to make certificates")
def test_the_documented_tls_setup_connects(tmp_path):
    # docs/campaigns.md: certificates for the scheduler and the workers, emaphm's own in
    # Dask's configuration, then --scheduler tls://...
    import subprocess

    import dask
    from distributed.security import Security

    def run(*args):
        subprocess.run(["openssl", *args], cwd=tmp_path, check=True, capture_output=True)

    run("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", "ca.key", "-out", "ca.pem",
        "-days", "2", "-subj", "/CN=emaphm-test-ca")
    run("req", "-newkey", "rsa:2048", "-nodes", "-keyout", "node.key", "-out", "node.csr",
        "-subj", "/CN=localhost")
    (tmp_path / "ext.cnf").write_text("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    run("x509", "-req", "-in", "node.csr", "-CA", "ca.pem", "-CAkey", "ca.key", "-CAcreateserial",
        "-out", "node.pem", "-days", "2", "-extfile", "ext.cnf")
    ca, cert, key = (str(tmp_path / n) for n in ("ca.pem", "node.pem", "node.key"))
    sec = Security(tls_ca_file=ca, tls_scheduler_cert=cert, tls_scheduler_key=key,
                   tls_worker_cert=cert, tls_worker_key=key, tls_client_cert=cert,
                   tls_client_key=key, require_encryption=True)
    with distributed.LocalCluster(n_workers=1, processes=False, protocol="tls", security=sec,
                                  dashboard_address=":0", host="127.0.0.1",
                                  silence_logs=50) as c:
        assert c.scheduler_address.startswith("tls://")
        with dask.config.set({"distributed.comm.tls.ca-file": ca,
                              "distributed.comm.tls.client.cert": cert,
                              "distributed.comm.tls.client.key": key}):
            ex = DaskExecutor(c.scheduler_address, warm=False, timeout=5)
            ex.check()
            assert sorted(v for _, v in ex.map_unordered(abs, [-1, -2])) == [1, 2]
        # the same scheduler asked without TLS: refused, with the hint
        plain = c.scheduler_address.replace("tls://", "tcp://")
        with pytest.raises(ValueError, match="did not answer as a Dask scheduler .*needs tls://"):
            DaskExecutor(plain, timeout=2).check()
