"""pytest plugin: the `vecat_network` fixture, one served line per test.

    @pytest.mark.vecat(slaves=4, args=["--twinsync", "gantry"])
    def test_my_master(vecat_network):
        run_my_master(vecat_network.iface)
        vecat_network.inject("drop", cable=1, count=3)

    @pytest.mark.vecat(network="machine.yaml")     # a network file instead of a line of drives
    def test_my_master_sees_the_door_open(vecat_network):
        vecat_network.set_input(slave=2, channel=0, value=1)

Outside `vecat exec --no-network -- pytest`, the tests that use the fixture are skipped with the reason.
"""

import pytest

from vecat.network import Network, NotInPrivateNamespace


def pytest_configure(config):
    config.addinivalue_line("markers",
                            "vecat(slaves=2, args=(), network=None): the line the vecat_network fixture serves")


@pytest.fixture
def vecat_network(request, tmp_path):
    marker = request.node.get_closest_marker("vecat")
    kwargs = dict(marker.kwargs) if marker else {}
    try:
        net = Network(slaves=kwargs.get("slaves", 2), args=kwargs.get("args", ()), workdir=str(tmp_path),
                      network=kwargs.get("network"))
    except NotInPrivateNamespace as e:
        pytest.skip(str(e))
    try:
        yield net
    finally:
        net.stop()  # also after a failing test: vecat stops, the veth pair goes
