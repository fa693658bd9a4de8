"""A pysoem test as a user would write it, against the vecat_network fixture.

    vecat exec --no-network -- python3 -m pytest python/examples
(pysoem from its own package; skipped where it is not installed.)
"""

import pytest

pysoem = pytest.importorskip("pysoem")


@pytest.mark.vecat(slaves=2)
def test_my_master_brings_the_line_to_op(vecat_network):
    master = pysoem.Master()
    master.open(vecat_network.iface)
    try:
        assert master.config_init() == 2
        for slave in master.slaves:
            assert slave.man == 0x00000A3C
        master.config_map()
        assert master.state_check(pysoem.SAFEOP_STATE, 50_000) == pysoem.SAFEOP_STATE
        master.state = pysoem.OP_STATE
        master.write_state()
        for _ in range(200):
            master.send_processdata()
            master.receive_processdata(2_000)
            if master.state_check(pysoem.OP_STATE, 5_000) == pysoem.OP_STATE:
                break
        assert master.state == pysoem.OP_STATE
        # What the test is really about: the master copes with lost frames.
        vecat_network.inject("drop", cable=0, count=3)
        for _ in range(10):
            master.send_processdata()
            master.receive_processdata(2_000)
    finally:
        master.close()
    # And the master broke none of the rules vecat checks (docs/master-report.md).
    assert vecat_network.report_findings() == []
