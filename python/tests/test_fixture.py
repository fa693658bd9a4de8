"""The kit's own tests: the fixture serves a line, the control socket injects faults, teardown cleans up.
Run under `vecat exec --no-network -- python3 -m pytest python/tests` (CI does, as root and as a user)."""

import os
import subprocess
import sys
import textwrap

import pytest

from ethercat_probe import broadcast_read_wkc, datagram_wkc


def links():
    out = subprocess.run(["ip", "-o", "link"], check=True, capture_output=True, text=True).stdout
    return {line.split(":")[1].strip().split("@")[0] for line in out.splitlines()}


def command_lines():
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                yield f.read().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue


def test_the_line_answers_with_one_count_per_slave(vecat_network):
    assert broadcast_read_wkc(vecat_network.iface) == 2


@pytest.mark.vecat(slaves=5)
def test_the_marker_sets_the_number_of_slaves(vecat_network):
    assert broadcast_read_wkc(vecat_network.iface) == 5


def test_a_fault_from_the_control_socket_reaches_the_wire(vecat_network):
    # Frames lost on the cable in front of slave 1 (position 0): the master gets no reply.
    reply = vecat_network.inject("drop", cable=0, count=2)
    assert reply.startswith("ok"), reply
    assert broadcast_read_wkc(vecat_network.iface) is None
    assert broadcast_read_wkc(vecat_network.iface) is None
    assert broadcast_read_wkc(vecat_network.iface) == 2  # the count is used up


def test_the_status_shows_each_slave(vecat_network):
    status = vecat_network.status()
    assert [s["slave"] for s in status] == ["0", "1"]
    assert all(s["al"] == "INIT" for s in status), status
    assert all(s["state"] == "SWITCH_ON_DISABLED" for s in status), status  # CiA 402 drives
    vecat_network.inject("link_down", slave=0, port=1, id="cut")
    assert vecat_network.status()[0]["lost_links"] == "0,1,0,0"


def test_an_unknown_fault_is_refused(vecat_network):
    from vecat import FaultError

    with pytest.raises(FaultError):
        vecat_network.inject("no_such_fault")


def test_the_capture_and_summary_are_written_when_the_network_stops(vecat_network):
    broadcast_read_wkc(vecat_network.iface)
    vecat_network.stop()
    assert os.path.getsize(vecat_network.pcap) > 0
    assert "frames received" in vecat_network.output()


IO_NETWORK = """
devices:
  - name: coupler
    device: coupler
  - name: valves
    device: digital-out
    upstream: coupler:3
  - name: sensors
    device: digital-in
    inputs:
      0: {signal: square, period_ms: 100}
      1: {wire: valves:0}
"""


def test_a_network_file_is_served_and_its_inputs_can_be_forced(tmp_path):
    from vecat import FaultError, NotInPrivateNamespace, start_network

    path = tmp_path / "io.yaml"
    path.write_text(IO_NETWORK)
    try:
        net = start_network(network=str(path), workdir=str(tmp_path))
    except NotInPrivateNamespace as e:
        pytest.skip(str(e))
    with net:
        assert broadcast_read_wkc(net.iface) == 3  # coupler, output and input terminal
        forced = net.set_input(slave=2, channel=1, value=1)
        assert forced in net.command("list")
        net.release_input(forced)
        assert forced not in net.command("list")
        with pytest.raises(FaultError):
            net.set_input(slave=1, channel=0, value=1)  # an output terminal has no inputs to force


def test_the_report_on_the_master_is_silent_for_a_master_that_breaks_no_rule(vecat_network):
    assert broadcast_read_wkc(vecat_network.iface) == 2
    assert vecat_network.report_findings() == []


def test_the_report_on_the_master_names_the_rule_a_master_broke(vecat_network):
    # APWR of the AL status register (0x0130, read-only) of the first slave instead of AL control.
    datagram_wkc(vecat_network.iface, 2, 0, 0x0130, b"\x02\x00")
    findings = vecat_network.report_findings()
    assert [f["rule"] for f in findings] == ["read-only-write"], findings
    assert findings[0]["severity"] == "warning"
    assert "0x0130" in findings[0]["message"]


def test_a_failing_test_leaves_no_interface_and_no_vecat_behind(tmp_path):
    before = links()
    failing = tmp_path / "test_fails.py"
    failing.write_text(textwrap.dedent("""
        def test_fails(vecat_network):
            assert False, "on purpose"
    """))
    (tmp_path / "conftest.py").write_text(open(os.path.join(os.path.dirname(__file__), "conftest.py")).read()
                                          .replace("os.path.dirname(__file__), \"..\"",
                                                   repr(os.path.join(os.path.dirname(__file__), ".."))))
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(failing)],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 1, r.stdout + r.stderr  # the test failed, as written
    assert "1 failed" in r.stdout
    assert links() == before
    assert not any(str(tmp_path) in args for args in command_lines())  # no vecat run of that test is left
