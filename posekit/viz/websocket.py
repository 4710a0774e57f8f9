"""The kernel's websocket without Nagle's delay: a Jupyter server setting that ``make studio`` (Voila) and
``make lab`` (JupyterLab) pass, so a widget's update reaches the browser as soon as the kernel sends it.

Introduced with the studio of ``notebooks/06_posing_studio.ipynb`` (``posekit bench studio`` measures it).
Tornado, under Jupyter Server and Voila, leaves Nagle's algorithm on for a websocket unless the application turns it
off, and Jupyter Server does not. While one message to the browser waits for its acknowledgement, the next small
one is held back until that acknowledgement comes, and the browser's side delays acknowledgements (Linux: up to
40 ms). A widget update is a burst of small messages (busy, the new values, idle), so nearly every update waited.
On this project's 2-core machine (loopback), each message of a studio update reached the page about 30 ms after
the kernel stamped it. Run in turn with and without this setting (three times each, 200 key presses; README, the
studio), a bare slider's round trip took 51.3 ms against 13.8 ms and a FABRIK + DLS studio update 67.2 ms against
32.6 ms (p50; the studio's page also without Voila's log forwarding in the second).
"""

from __future__ import annotations

import socket

from jupyter_server.services.kernels.connection.channels import ZMQChannelsWebsocketConnection

__all__ = ["NoDelayConnection", "CONNECTION_CLASS", "server_flags"]


class NoDelayConnection(ZMQChannelsWebsocketConnection):
    """Jupyter Server's kernel websocket connection that sets ``TCP_NODELAY`` on the browser's socket as it connects
    (each message leaves at once) and logs the option as read back from the socket."""

    def connect(self):
        handler = self.websocket_handler
        handler.set_nodelay(True)
        stream = getattr(handler.ws_connection, "stream", None)
        sock = getattr(stream, "socket", None)
        if sock is not None and sock.family in (socket.AF_INET, socket.AF_INET6):
            on = sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY)
            self.log.info("kernel %s: websocket TCP_NODELAY=%d", self.kernel_id, int(bool(on)))
        return super().connect()


CONNECTION_CLASS = f"{__name__}.{NoDelayConnection.__name__}"
"""The class's dotted name, for ``--ServerApp.kernel_websocket_connection_class`` (JupyterLab) and
``--Voila.kernel_websocket_connection_class`` (Voila)."""


def server_flags(app: str) -> list[str]:
    """The command-line arguments (a list of one) that set the connection class for ``app`` (``"voila"`` or
    ``"lab"``: JupyterLab and any Jupyter Server application)."""
    owner = {"voila": "Voila", "lab": "ServerApp"}[app]
    return [f"--{owner}.kernel_websocket_connection_class={CONNECTION_CLASS}"]
