"""The controller's dashboard server (port 29999) through ur_rtde's ``dashboard_client``: what an operator does at
the pendant, for benchmarks and tests against the twin (a run never unlocks a protective stop by itself)."""

from __future__ import annotations

from bt_grasp.hardware.ur_lib import UrRtdeUnavailable


def unlock_protective_stop(host: str) -> bool:
    """Unlock a protective stop (refused by the controller within 5 s of the stop, or the twin's
    ``--unlock-delay``); True when it was unlocked."""
    try:
        import dashboard_client
    except ImportError:
        raise UrRtdeUnavailable("the dashboard client") from None
    dashboard = dashboard_client.DashboardClient(host)
    try:
        dashboard.connect()
        dashboard.unlockProtectiveStop()
        return "PROTECTIVE_STOP" not in str(dashboard.safetystatus())
    except RuntimeError:
        return False
    finally:
        dashboard.disconnect()
