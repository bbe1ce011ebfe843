"""Which addresses bt_grasp's servers bind to: a loopback address by default, another only with a warning.

The live view and its control (Foxglove WebSocket), the controller twin and the resident process all serve
protocols without authentication, so each binds to 127.0.0.1 unless the user names another address, and every
one of them asks this module whether the address is one only this machine can reach.
"""

from __future__ import annotations

import ipaddress


def is_loopback(host: str) -> bool:
    """True for an address only this machine can reach (127.0.0.0/8, ::1, localhost)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def exposure_warning(option: str, host: str, what: str, tunnel_port: int) -> str:
    """The one warning printed when a server is told to bind to an address other machines can reach."""
    return (
        f"warning: {option} {host} serves {what} to anyone who can reach the port: the protocol has no "
        f"authentication. To reach it from another machine, keep the default 127.0.0.1 and tunnel "
        f"(ssh -L {tunnel_port}:127.0.0.1:{tunnel_port} this-host); see docs/security.md."
    )
