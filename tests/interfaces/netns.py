# SPDX-License-Identifier: Apache-2.0
"""A network of the test's own, shaped like a team laptop's: the test process moves into a new
network namespace (unshare(CLONE_NEWNET), through libc) where it brings loopback up *without* the
MULTICAST flag, as Linux leaves it, and adds a veth pair whose one end holds an address and the
default route. Everything the test and the simulators it starts send stays inside; nothing
reaches the machine's real interfaces.

Addresses are from TEST-NET-1 (RFC 5737), which nothing on a real network uses.
"""
import ctypes
import ctypes.util
import os
import subprocess

CLONE_NEWNET = 0x40000000
LAN_ADDRESS = "192.0.2.1"    # the laptop's own address on its network
LAN_GATEWAY = "192.0.2.254"  # the default route's gateway (never answers: nothing is there)
LAN_INTERFACE = "veth0"


def _ip(*args):
    subprocess.run(["ip", *args], check=True, capture_output=True, text=True)


def enter(default_route=True):
    """Moves this process into a fresh network namespace and builds the network there. Returns
    None, or the reason it cannot (no permission for namespaces, no `ip`), for skipTest."""
    libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
    if libc.unshare(CLONE_NEWNET) != 0:
        return f"cannot make a network namespace here: {os.strerror(ctypes.get_errno())}"
    try:
        _ip("link", "set", "lo", "up")
        _ip("link", "set", "lo", "multicast", "off")  # as on a normal laptop
        _ip("link", "add", LAN_INTERFACE, "type", "veth", "peer", "name", "veth1")
        _ip("addr", "add", LAN_ADDRESS + "/24", "dev", LAN_INTERFACE)
        _ip("link", "set", LAN_INTERFACE, "up")
        _ip("link", "set", "veth1", "up")
        if default_route:
            _ip("route", "add", "default", "via", LAN_GATEWAY, "dev", LAN_INTERFACE)
    except FileNotFoundError:
        return "the `ip` command (iproute2) is missing"
    except subprocess.CalledProcessError as e:
        return f"cannot build the test network: {' '.join(e.cmd)}: {e.stderr.strip()}"
    return None


def remove_default_route():
    """Leaves the namespace with no default route (a laptop with no network)."""
    _ip("route", "del", "default")


def set_loopback_multicast(on):
    """Sets or clears loopback's MULTICAST flag (`ip link set lo multicast on|off`)."""
    _ip("link", "set", "lo", "multicast", "on" if on else "off")
