"""Testing EtherCAT masters against vecat, the virtual EtherCAT machine.

`start_network()` serves a line of virtual slaves on a veth pair of its own, with a fault-injection control
socket and a capture; the pytest plugin (`vecat.pytest_plugin`) gives each test one as the `vecat_network`
fixture. Interfaces can only be made inside a network namespace the test owns: run pytest under
`vecat exec --no-network -- pytest ...` (no root needed), which also tells the fixture where vecat is.
"""

from vecat.network import FaultError, Network, NotInPrivateNamespace, start_network

__all__ = ["FaultError", "Network", "NotInPrivateNamespace", "start_network"]
