"""One served line of virtual slaves: `vecat run` on one end of a veth pair, the other end for the master."""

import itertools
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import xml.etree.ElementTree as ElementTree

_counter = itertools.count(1)


class NotInPrivateNamespace(RuntimeError):
    """Raised when interfaces would be made outside a network namespace that this test run owns."""


class FaultError(RuntimeError):
    """vecat refused a control command (its reply starts with "error")."""


def _vecat_binary(explicit=None):
    for candidate in (explicit, os.environ.get("VECAT_BIN"), shutil.which("vecat")):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    raise FileNotFoundError("vecat not found: set VECAT_BIN or put vecat on PATH")


def _ip(*args):
    subprocess.run(["ip", *args], check=True, capture_output=True)


class Network:
    """A line of virtual slaves served by `vecat run`: `slaves` vecat drives, or the devices and cabling of a
    network file (`network`, docs/network-file.md).

    iface: the master's end of the veth pair (open it with your master); control: the fault-injection socket;
    pcap: the capture of every frame in and out and report: the report on the master (JUnit XML, see
    docs/master-report.md), both written when the network stops; log: vecat's output.
    """

    def __init__(self, slaves=2, args=(), vecat=None, workdir=None, startup_timeout=20.0, network=None):
        if os.environ.get("VECAT_EXEC") != "1":
            raise NotInPrivateNamespace(
                "vecat networks are made in a private network namespace: run the tests under "
                "`vecat exec --no-network -- pytest ...`")
        n = next(_counter)
        self.iface = f"vm{os.getpid() % 100000}x{n}"[:15]
        self.slave_iface = f"vs{os.getpid() % 100000}x{n}"[:15]
        self.workdir = workdir or tempfile.mkdtemp(prefix="vecat-")
        self.control = os.path.join(self.workdir, "control.sock")
        self.pcap = os.path.join(self.workdir, "capture.pcapng")
        self.log = os.path.join(self.workdir, "vecat.log")
        self.report = os.path.join(self.workdir, "master-report.xml")
        self._proc = None
        _ip("link", "add", "name", self.iface, "type", "veth", "peer", "name", self.slave_iface)
        try:
            _ip("link", "set", "dev", self.iface, "up")
            _ip("link", "set", "dev", self.slave_iface, "up")
            served = ["--network", str(network)] if network else ["--slaves", str(slaves)]
            cmd = [_vecat_binary(vecat), "run", "--iface", self.slave_iface, *served,
                   "--control", self.control, "--pcap", self.pcap, "--report", self.report, *args]
            with open(self.log, "w") as log:
                self._proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT)
            self._wait_ready(startup_timeout)
        except BaseException:
            self.stop()
            raise

    def _wait_ready(self, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self._proc.poll() is not None:
                raise RuntimeError(f"vecat run ended with {self._proc.returncode}: {self.output()}")
            # vecat run opens its socket, then the control socket, then prints this line and serves.
            if "Ctrl-C stops" in self.output() and os.path.exists(self.control):
                return
            time.sleep(0.01)
        raise TimeoutError(f"vecat run did not start within {timeout} s: {self.output()}")

    def output(self):
        """What vecat printed so far."""
        try:
            with open(self.log) as f:
                return f.read()
        except OSError:
            return ""

    def command(self, line):
        """Sends one control command ("inject KIND key=value...", "clear ID|KIND|all", "list")."""
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(10)
            s.connect(self.control)
            s.sendall(line.encode() + b"\n")
            s.shutdown(socket.SHUT_WR)
            reply = b""
            while chunk := s.recv(4096):
                reply += chunk
        text = reply.decode().strip()
        if text.startswith("error"):
            raise FaultError(text)
        return text

    def inject(self, kind, **params):
        """Injects a fault (see `vecat fault kinds`): inject("drop", cable=1, count=5). Returns vecat's reply."""
        return self.command(" ".join(["inject", kind, *(f"{k}={v}" for k, v in params.items())]))

    def clear(self, what="all"):
        return self.command(f"clear {what}")

    def status(self):
        """What each slave shows now: a list (by position) of dicts of the control socket's `status` line,
        e.g. {"slave": "0", "al": "OP", "al_code": "0x0000", "lost_links": "0,0,0,0", "statusword": "0x0237",
        "state": "OPERATION_ENABLED", "position": "1000", ...}; the CiA 402 keys only for CiA 402 devices."""
        lines = self.command("status").splitlines()[1:]
        return [dict(kv.split("=", 1) for kv in line.split()) for line in lines]

    def set_input(self, slave, channel, value):
        """Forces an input of a built-in input terminal of a network file (slave: its position on the line)
        to value until release_input() with the id this returns (fault set_input)."""
        reply = self.inject("set_input", slave=slave, channel=channel, value=value)
        return reply.split()[1]  # "ok ID"

    def release_input(self, forced_id):
        """The input follows its signal or wire again."""
        return self.clear(forced_id)

    def report_findings(self):
        """The rules of the report on the master that the master broke, as dicts with the rule's id, its
        severity ("error" or "warning") and what happened; [] when it broke none. Stops the network first
        (the report is written when vecat stops)."""
        self.stop()
        findings = []
        for case in ElementTree.parse(self.report).getroot().iter("testcase"):
            failure = case.find("failure")
            if failure is not None:
                findings.append({"rule": case.get("name").split(":")[0], "severity": failure.get("type"),
                                 "message": failure.get("message")})
        return findings

    def stop(self):
        """Stops vecat (its summary and the capture are written) and removes the veth pair."""
        if self._proc and self._proc.poll() is None:
            self._proc.send_signal(signal.SIGINT)
            try:
                self._proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        try:
            _ip("link", "del", "dev", self.iface)  # deletes both ends
        except (subprocess.CalledProcessError, FileNotFoundError):
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


def start_network(slaves=2, args=(), vecat=None, workdir=None, network=None):
    """Serves `slaves` virtual drives, or the network file `network` (plus any `vecat run` options in args);
    use it as a context manager."""
    return Network(slaves=slaves, args=args, vecat=vecat, workdir=workdir, network=network)
