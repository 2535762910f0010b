"""The command runtime of every command (issue 36 items 1, 3, 12): a --scheduler that is not a
Dask scheduler fails fast in one line; the local cluster speaks TLS with a certificate of its own,
so no other process can connect; every command checks its output, report directory, disk space
and lock before any work; errors map to one line naming the real path; Ctrl-C says what each
command kept."""
import contextlib
import http.server
import json
import os
import signal
import socket
import threading
import time
from pathlib import Path

import pytest

from rotorsweep.pipeline import cli, cluster, cube, fileio, gridsize, preflight, sweep
from tests.harness import run_cli, stop, wait_for_file, wait_for_parts

CONFIG = Path(__file__).parents[1] / "configs"
LISTEN_S = 60       # the fake services stop by themselves after this, whatever the test does


def nothing_left(out):
    return not cube.parts_dir(out).exists() and not fileio.lock_path(out).exists() and not Path(out).exists()


# --- item 1: a --scheduler that is not a Dask scheduler ---------------------------------------

@contextlib.contextmanager
def tcp_listener(reply):
    """A TCP service on 127.0.0.1 that accepts and sends `reply` (None: says nothing); it
    stops when the block ends or after LISTEN_S. Yields its address."""
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(LISTEN_S)
    held = []

    def serve():
        with contextlib.suppress(OSError):
            while True:
                conn, _ = server.accept()
                held.append(conn)            # keep it open: a silent peer, not a closed one
                if reply:
                    conn.sendall(reply)

    threading.Thread(target=serve, daemon=True).start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        server.close()
        for conn in held:
            conn.close()


@contextlib.contextmanager
def http_server():
    """An HTTP server on 127.0.0.1 (it answers a Dask frame with nothing until the peer gives up)."""
    class Quiet(http.server.BaseHTTPRequestHandler):
        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Quiet)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    timer = threading.Timer(LISTEN_S, server.shutdown)
    timer.start()
    try:
        yield f"tcp://127.0.0.1:{server.server_address[1]}"
    finally:
        timer.cancel()
        server.shutdown()
        server.server_close()


SERVICES = {
    "silent listener": lambda: tcp_listener(None),
    "http server": http_server,
    # an HTTP reply read as a Dask frame header: b"HTTP/1.1" as a length is 3.07 EiB
    "garbage answer": lambda: tcp_listener(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n"),
}


@pytest.mark.parametrize("service", SERVICES)
@pytest.mark.parametrize("command", ["run", "continue"])
def test_a_scheduler_address_that_is_no_dask_scheduler_is_one_line(service, command, small_config, tmp_path, capsys):
    out = tmp_path / "s.nc"
    with SERVICES[service]() as address:
        t0 = time.monotonic()
        args = [command, *([small_config] if command == "run" else []), "-o", out]
        rc, err = run_cli(capsys, *args, "--scheduler", address, "--scheduler-timeout", "1")
        took = time.monotonic() - t0
    assert rc == 2 and address in err and len(err.strip().splitlines()) == 1, err
    assert "EiB" not in err or "does not speak Dask's protocol" in err
    assert took < 10, took               # 1 s to answer, not a hang (before: 90 s, 300 s, killed)
    assert nothing_left(out)


def test_the_handshake_tells_a_scheduler_from_a_worker():
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, processes=False, protocol="tcp://", host="127.0.0.1",
                      dashboard_address=None) as local:
        cluster.check_scheduler(local.scheduler_address)
        worker = next(iter(local.workers.values())).address
        with pytest.raises(cluster.SweepError, match="a Dask Worker answers there, not a scheduler"):
            cluster.check_scheduler(worker)


@pytest.mark.parametrize("text", ["0", "-1", "nan", "inf", "soon"])
def test_the_scheduler_timeout_is_checked_at_parsing(text, capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(["run", "--scheduler", "tcp://127.0.0.1:1", "--scheduler-timeout", text])
    assert stop.value.code == 2 and "--scheduler-timeout" in capsys.readouterr().err


# --- item 3: the local cluster is authenticated ------------------------------------------------

OTHER_PROCESS = """
import sys
from dask.distributed import Client
from distributed.security import Security
security = Security.temporary() if sys.argv[2] == "own-certificate" else None
try:
    with Client(sys.argv[1], timeout="5s", security=security) as c:
        print("CONNECTED", c.run(lambda: 1))
except Exception as exc:
    print("REFUSED", type(exc).__name__)
"""


@pytest.fixture(scope="module")
def local_sweep_cluster():
    client, local = cluster.connect(1, None)          # the cluster run, continue and backbone start
    try:
        yield client, local
    finally:
        cluster.close(client, local)


@pytest.mark.parametrize("how", ["plain", "own-certificate"])
def test_another_process_cannot_connect_to_the_local_cluster(local_sweep_cluster, how, tmp_path):
    import subprocess
    import sys

    client, local = local_sweep_cluster
    address = local.scheduler_address
    assert address.startswith("tls://127.0.0.1:")
    tcp = "tcp://" + address.split("://", 1)[1]
    for target in (address, tcp):
        proc = subprocess.run([sys.executable, "-c", OTHER_PROCESS, target, how], capture_output=True, text=True,
                              timeout=120)
        assert "REFUSED" in proc.stdout and "CONNECTED" not in proc.stdout, (target, proc.stdout, proc.stderr)
    assert client.submit(lambda: 41 + 1).result() == 42           # the driver still can


def dask_answers(address, security):
    """Whether a Dask server at `address` answers an identity request from a client with
    `security` (a connection a client could then run code over), within 1 s (a Dask server on
    127.0.0.1 answers in ms; an HTTP dashboard says nothing)."""
    import asyncio

    from distributed.comm import connect as dask_connect

    async def ask():
        comm = await dask_connect(address, timeout=1, **security.get_connection_args("client"))
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        asyncio.run(asyncio.wait_for(ask(), 1))
        return True
    except Exception:
        return False


def test_no_port_of_a_running_sweep_answers_another_process(tmp_path):
    """Every port the processes of a running `rotorsweep run` listen on (scheduler, nannies,
    workers, dashboards) refuses this test process: without a certificate, over TCP or TLS, and
    with a certificate of its own."""
    import subprocess

    import psutil
    from distributed.security import Security

    from tests.test_pipeline import CLI
    from tests.test_reliability import LONG

    cfg = tmp_path / "long.toml"
    cfg.write_text(LONG)
    out = tmp_path / "long.nc"
    proc = subprocess.Popen(CLI + ["run", str(cfg), "-o", str(out), "--workers", "2", "--chunk-points", "16", "-q"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        wait_for_parts(cube.parts_dir(out), proc)
        driver = psutil.Process(proc.pid)
        ports = {c.laddr.port for p in [driver, *driver.children(recursive=True)]
                 for c in p.net_connections(kind="inet") if c.status == psutil.CONN_LISTEN}
        assert len(ports) >= 3, ports               # the scheduler and two workers at least
        assert proc.poll() is None                  # probed while the sweep runs
        foreign = Security.temporary()
        for port in sorted(ports):
            assert not dask_answers(f"tcp://127.0.0.1:{port}", Security()), port
            assert not dask_answers(f"tls://127.0.0.1:{port}", foreign), port
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


def test_a_scheduler_given_with_tls_files_answers_and_without_them_is_one_line(local_sweep_cluster, tmp_path):
    _, local = local_sweep_cluster
    files = pem_files(local.security, tmp_path)
    address = local.scheduler_address
    cluster.check_scheduler(cluster.Scheduler(address, files["ca"], files["cert"], files["key"]))
    cluster.check_scheduler(local)          # the Python API takes the running cluster, with its certificate
    with pytest.raises(cluster.SweepError, match="TLS setting"):
        cluster.check_scheduler(cluster.Scheduler(address, timeout=2))
    with pytest.raises(cluster.SweepError, match="--tls-key missing"):
        cluster.check_scheduler(cluster.Scheduler(address, files["ca"], files["cert"]))
    with pytest.raises(cluster.SweepError, match="nosuch.pem: not a readable file"):
        cluster.check_scheduler(cluster.Scheduler(address, files["ca"], files["cert"], tmp_path / "nosuch.pem"))


# --- item 12: every command checks before any work ---------------------------------------------

@pytest.fixture
def no_work(monkeypatch):
    """Any computation started fails the test: the checks must come first."""
    def work(*args, **kwargs):
        raise AssertionError("work started before the checks")

    from rotorsweep.pipeline import backbone, continuation, modes
    for module, name in ((sweep, "run"), (continuation, "run"), (backbone, "run"), (modes, "command")):
        monkeypatch.setattr(module, name, work)


COMMANDS = {
    "run": lambda cfg, out: ["run", cfg, "-o", out],
    "continue": lambda cfg, out: ["continue", "-o", out],
    "backbone": lambda cfg, out: ["backbone", CONFIG / "filipkovsky2010_symmetric.toml", "-o", out],
    "modes": lambda cfg, out: ["modes", cfg, "-o", out],
}


@pytest.mark.parametrize("command", COMMANDS)
def test_an_output_that_is_a_directory_is_refused_before_any_work(command, small_config, tmp_path, capsys, no_work):
    out = tmp_path / "adir"
    out.mkdir()
    rc, err = run_cli(capsys, *COMMANDS[command](small_config, out), *(["--overwrite"] if command != "modes" else []))
    assert rc == 2 and f"{out} is a directory" in err and len(err.strip().splitlines()) == 1, err
    assert not fileio.lock_path(out).exists() and not cube.parts_dir(out).exists()


@pytest.mark.parametrize("command", COMMANDS)
def test_an_output_under_a_file_is_refused_before_any_work(command, small_config, tmp_path, capsys, no_work):
    (tmp_path / "afile").write_text("x")
    rc, err = run_cli(capsys, *COMMANDS[command](small_config, tmp_path / "afile" / "o.nc"))
    assert rc == 2 and "afile is not a directory" in err and ".tmp" not in err, err


@pytest.mark.parametrize("command", COMMANDS)
def test_a_conflicting_report_directory_is_refused_before_any_work(command, small_config, tmp_path, capsys, no_work):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("mine")
    out = tmp_path / "o.nc"
    rc, err = run_cli(capsys, *COMMANDS[command](small_config, out), "--report", mine)
    assert rc == 2 and "holds no rotorsweep report" in err, err
    assert nothing_left(out)


@pytest.mark.parametrize("command", COMMANDS)
def test_too_little_disk_space_is_refused_before_any_work(command, small_config, tmp_path, capsys, no_work, monkeypatch):
    real = os.statvfs

    class Full:
        def __init__(self, path):
            self.st = real(path)
            self.f_frsize, self.f_bavail = self.st.f_frsize, 1

    monkeypatch.setattr(preflight.os, "statvfs", Full)
    out = tmp_path / "o.nc"
    rc, err = run_cli(capsys, *COMMANDS[command](small_config, out))
    assert rc == 2 and "MiB free" in err and str(out) in err, err
    assert nothing_left(out)


def test_a_sweep_asks_for_room_for_its_parts_and_its_cube(small_config):
    from rotorsweep.pipeline import config

    cfg = config.load_config(small_config)
    assert preflight.sweep_bytes(cfg) == (2 * cfg.n_points * gridsize.bytes_per_point(cfg.data)
                                          + preflight.MIN_FREE_BYTES)


def test_an_unwritable_output_directory_is_refused_before_any_work(small_config, tmp_path, capsys, no_work,
                                                                   monkeypatch):
    # the tests may run as root, for whom every directory is writable: os.access says no here
    monkeypatch.setattr(preflight.os, "access", lambda path, mode: False)
    rc, err = run_cli(capsys, "continue", "-o", tmp_path / "o.nc")
    assert rc == 2 and f"{tmp_path}: permission denied" in err, err


@pytest.mark.parametrize("command", ["run", "continue", "backbone"])
def test_a_locked_output_is_refused_before_any_work(command, small_config, tmp_path, capsys, no_work):
    out = tmp_path / "o.nc"
    with fileio.output_lock(out, "first.toml"):
        rc, err = run_cli(capsys, *COMMANDS[command](small_config, out))
        assert rc == 2 and f"pid {os.getpid()}" in err and "first.toml" in err, err
        assert fileio.lock_path(out).exists()           # the first run's lock is left alone
    assert nothing_left(out)


def test_report_checks_its_directory_before_drawing(tmp_path, capsys, monkeypatch):
    import rotorsweep.pipeline as pipeline

    monkeypatch.setattr(pipeline, "make_report", lambda *a, **k: pytest.fail("drawn before the checks"))
    (tmp_path / "afile").write_text("x")
    rc, err = run_cli(capsys, "report", tmp_path / "c.nc", "-o", tmp_path / "afile" / "r")
    assert rc == 2 and "afile is not a directory" in err, err


# --- item 12: errors name the real path --------------------------------------------------------

def test_a_write_error_names_the_output_not_its_temp_file(tmp_path):
    target = tmp_path / "r.nc"
    with pytest.raises(OSError) as err:
        with fileio.atomic_path(target) as tmp:
            raise OSError(28, "No space left on device", tmp)
    assert cli.error_text(err.value) == f"{target}: No space left on device"
    with pytest.raises(OSError) as err:
        with fileio.atomic_path(target):
            raise RuntimeError("NetCDF: HDF error")        # netCDF-C on a full disk
    assert cli.error_text(err.value).startswith(f"{target}: netCDF write failed (NetCDF: HDF error")
    assert list(tmp_path.iterdir()) == []                   # no temp file left


def test_a_full_disk_in_continue_is_one_line_naming_the_output(tmp_path, monkeypatch):
    import xarray as xr

    from rotorsweep.pipeline import results

    def hdf_error(*_, **__):
        raise RuntimeError("NetCDF: HDF error")

    monkeypatch.setattr("netCDF4.Dataset", hdf_error)
    with pytest.raises(OSError) as err:
        results.write(xr.Dataset({"x": ("i", [1.0])}), tmp_path / "c.nc")
    assert cli.error_text(err.value).startswith(f"{tmp_path / 'c.nc'}: netCDF write failed")


def test_dask_giving_up_on_a_task_is_one_line():
    from distributed.scheduler import KilledWorker

    from types import SimpleNamespace

    text = cli.error_text(KilledWorker("continue_line-abc", SimpleNamespace(address="tcp://127.0.0.1:1"), 3))
    assert text.startswith("Dask gave up on a task: Attempted to run task 'continue_line-abc' on 4 different")
    assert "\n" not in text


# --- Ctrl-C: each command says what it kept ----------------------------------------------------

@pytest.mark.parametrize("command, expected", [
    ("run", "interrupted; finished chunks are kept, rerun with --resume"),
    ("continue", None), ("backbone", None),
    ("report", "interrupted; nothing was written, the report directory is as it was"),
    ("point", "interrupted"),
])
def test_ctrl_c_tells_each_commands_truth(command, expected):
    args = cli.build_parser().parse_args({"run": ["run"], "continue": ["continue"], "backbone": ["backbone", "x.toml"],
                                          "report": ["report", "c.nc"], "point": ["point"]}[command])
    text = cli.interrupted_text(args)
    if expected is None:         # resumable once the command takes --resume, never a false promise
        expected = ("interrupted; finished lines are kept, rerun with --resume" if hasattr(args, "resume")
                    else "interrupted; nothing was written, the output is as it was")
    assert text == expected


def test_ctrl_c_in_continue_says_what_it_kept(tmp_path, monkeypatch, capsys):
    from rotorsweep.pipeline import continuation

    def interrupted(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(5)
        raise AssertionError("SIGINT was not delivered")

    monkeypatch.setattr(continuation, "run", interrupted)
    args = cli.build_parser().parse_args(["continue"])
    assert cli.main(["continue", "-o", str(tmp_path / "c.nc")]) == 130
    assert capsys.readouterr().err == f"rotorsweep: {cli.interrupted_text(args)}\n"


def pem_files(security, tmp_path):
    """The CA, certificate and key of a Security.temporary() (PEM texts; one self-signed
    certificate for all three) written to files: what a site's CA would issue to the scheduler,
    the workers and the client."""
    files = {}
    for name, pem in (("ca", security.tls_ca_file), ("cert", security.tls_client_cert),
                      ("key", security.tls_client_key)):
        files[name] = tmp_path / f"{name}.pem"
        files[name].write_text(pem)
    return files


@pytest.mark.slow    # ~50 s on 2 busy cores (the worker loads the scene's kernels): make test-slow
def test_a_secure_dask_cli_cluster_as_the_readme_starts_it(small_config, tmp_path, capsys):
    """The README's multi-node recipe on 127.0.0.1: `dask scheduler` and `dask worker` with TLS
    files; `rotorsweep run --scheduler tls://... --tls-*` sweeps on it, a client without the
    files is one line."""
    import subprocess

    from tests.test_reliability_cluster import DASK

    from distributed.security import Security

    files = pem_files(Security.temporary(), tmp_path)
    tls = ["--tls-ca-file", str(files["ca"]), "--tls-cert", str(files["cert"]), "--tls-key", str(files["key"])]
    sched_file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([DASK, "scheduler", "--host", "tls://127.0.0.1", "--port", "0", *tls,
                               "--dashboard-address", "127.0.0.1:0", "--scheduler-file", str(sched_file)],
                              stderr=subprocess.DEVNULL)]
    try:
        wait_for_file(sched_file)
        address = json.loads(sched_file.read_text())["address"]
        assert address.startswith("tls://127.0.0.1:")
        procs.append(subprocess.Popen([DASK, "worker", address, "--nthreads", "1", "--no-nanny", *tls],
                                      stderr=subprocess.DEVNULL))
        out = tmp_path / "tls.nc"
        rc, err = run_cli(capsys, "run", small_config, "-o", out, "-q", "--scheduler", address, *tls)
        assert rc == 0, err
        assert cube.open_cube(out)["orbit_status"].size == 22
        rc, err = run_cli(capsys, "run", small_config, "-o", tmp_path / "no.nc", "--scheduler", address,
                          "--scheduler-timeout", "2")
        assert rc == 2 and "TLS setting" in err, err
    finally:
        stop(procs)
