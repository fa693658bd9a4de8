"""A few raw EtherCAT datagrams from Python (AF_PACKET), enough for the kit's own tests."""

import socket
import struct

ETHERTYPE = 0x88A4
PACKET_OUTGOING = 4


def broadcast_read_wkc(iface, timeout=0.5):
    """Sends one BRD of register 0x0000 (ETG.1000.4 5.4.2) and returns its working counter: the number of
    slaves that answered; None when no reply came."""
    return datagram_wkc(iface, 7, 0, 0x0000, b"\0\0", timeout)


def datagram_wkc(iface, command, adp, ado, data, timeout=0.5):
    """Sends one datagram (command, position or station, register, data) and returns its working counter;
    None when no reply came."""
    with socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETHERTYPE)) as s:
        s.bind((iface, ETHERTYPE))
        s.settimeout(timeout)
        index = 0x5A
        datagram = struct.pack("<BBHHHH", command, index, adp, ado, len(data), 0) + data + struct.pack("<H", 0)
        header = struct.pack("<H", len(datagram) | 0x1000)
        frame = b"\xff" * 6 + b"\x02\0\0\0\0\x01" + struct.pack(">H", ETHERTYPE) + header + datagram
        s.send(frame.ljust(60, b"\0"))
        while True:
            try:
                data, addr = s.recvfrom(1514)
            except socket.timeout:
                return None
            if addr[2] == PACKET_OUTGOING or len(data) < 16 + 12 or data[17] != index:
                continue
            return struct.unpack_from("<H", data, 16 + 12)[0]
