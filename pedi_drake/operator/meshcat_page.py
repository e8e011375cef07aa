"""MeshcatPage: a stand-in for the browser page of a Meshcat, for tests, benchmarks and scripts.

It connects to the Meshcat server over its WebSocket as a browser does (the server then counts
one active connection) and sends what the page sends when a person clicks a button or moves a
slider: a MessagePack map, {"type": "button", "name": ...} or {"type": "slider", "name": ...,
"value": ...}, in a masked binary frame (RFC 6455). So a scripted operator drives the Meshcat
panel (pedi_drake.operator.meshcat_panel) through the same path as a person: the server's
WebSocket, its click counts and slider values. What the server sends back (the scene) is read
and dropped on a thread of its own, so the server never has to hold it for a slow reader.

The page runs in the process of the Meshcat it is given: every call returns once the server has
taken the message in (the click counted, the slider set, the connection counted), so a
simulation advanced after the call sees it.

Use it as a context manager; leaving the block closes the connection (the operator falls silent).
"""

import base64
import math
import os
import socket
import struct
import threading
import time

from pydrake.geometry import Meshcat

_OPCODE_BINARY = 0x2
_FIN = 0x80
_MASKED = 0x80
_CONNECT_TIMEOUT = 10.0  # [s]
# How long a call waits for the server to take its message in, and how often it looks [s].
_TAKEN_TIMEOUT = 10.0
_POLL = 0.001


def _msgpack_string(text: str) -> bytes:
    data = text.encode()
    if len(data) < 32:
        return bytes([0xA0 | len(data)]) + data
    if len(data) < 256:
        return bytes([0xD9, len(data)]) + data
    return b"\xda" + struct.pack(">H", len(data)) + data


def msgpack_map(fields: dict[str, str | float]) -> bytes:
    """MessagePack encoding of a small map of strings to strings or floats (all the page sends)."""
    out = bytes([0x80 | len(fields)])
    for key, value in fields.items():
        out += _msgpack_string(key)
        out += _msgpack_string(value) if isinstance(value, str) else b"\xcb" + struct.pack(">d", float(value))
    return out


def websocket_frame(payload: bytes, mask: bytes) -> bytes:
    """One final binary WebSocket frame of `payload`, masked with the 4 bytes `mask` (a client's frame)."""
    n = len(payload)
    if n < 126:
        header = bytes([_FIN | _OPCODE_BINARY, _MASKED | n])
    elif n < 1 << 16:
        header = bytes([_FIN | _OPCODE_BINARY, _MASKED | 126]) + struct.pack(">H", n)
    else:
        header = bytes([_FIN | _OPCODE_BINARY, _MASKED | 127]) + struct.pack(">Q", n)
    masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
    return header + mask + masked


class MeshcatPage:
    """A connection to `meshcat` that clicks its buttons and sets its sliders (see the module docstring)."""

    def __init__(self, meshcat: Meshcat):
        self._meshcat = meshcat
        self._port = meshcat.port()
        self._socket: socket.socket | None = None
        self._reader: threading.Thread | None = None
        self._lock = threading.Lock()

    def __enter__(self) -> "MeshcatPage":
        self.connect()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def connect(self) -> None:
        """Opens the WebSocket (the HTTP upgrade handshake) and starts draining what the server sends."""
        connections = self._meshcat.GetNumActiveConnections()
        sock = socket.create_connection(("127.0.0.1", self._port), timeout=_CONNECT_TIMEOUT)
        key = base64.b64encode(os.urandom(16)).decode()
        sock.sendall(
            (
                f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{self._port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
            ).encode()
        )
        answer = b""
        while b"\r\n\r\n" not in answer:
            chunk = sock.recv(4096)
            if not chunk:
                raise ConnectionError("the Meshcat server closed the connection during the WebSocket handshake")
            answer += chunk
        if not answer.startswith(b"HTTP/1.1 101"):
            raise ConnectionError(f"the Meshcat server refused the WebSocket: {answer.splitlines()[0]!r}")
        sock.settimeout(None)
        self._socket = sock
        self._reader = threading.Thread(target=self._drain, name="meshcat_page_reader", daemon=True)
        self._reader.start()
        self._wait(lambda: self._meshcat.GetNumActiveConnections() > connections, "the connection")

    def _wait(self, taken, what: str) -> None:
        """Returns once `taken()` is true; raises TimeoutError after _TAKEN_TIMEOUT."""
        deadline = time.monotonic() + _TAKEN_TIMEOUT
        while not taken():
            if time.monotonic() > deadline:
                raise TimeoutError(f"the Meshcat server did not take in {what} within {_TAKEN_TIMEOUT:.0f} s")
            time.sleep(_POLL)

    def _drain(self) -> None:
        sock = self._socket
        try:
            while sock is not None and sock.recv(1 << 16):
                pass
        except OSError:
            pass  # closed by `close`

    def send(self, fields: dict[str, str | float]) -> None:
        """Sends one message of the page (a MessagePack map)."""
        if self._socket is None:
            raise ConnectionError("the page is not connected")
        frame = websocket_frame(msgpack_map(fields), os.urandom(4))
        with self._lock:
            self._socket.sendall(frame)

    def click(self, button: str) -> None:
        """Clicks `button` once (as a mouse click or its key on the page)."""
        clicks = self._meshcat.GetButtonClicks(button)
        self.send({"type": "button", "name": button})
        self._wait(lambda: self._meshcat.GetButtonClicks(button) > clicks, f"the click on {button!r}")

    def set_slider(self, slider: str, value: float) -> None:
        """Moves `slider` to `value` (the page sends whatever it is given: no clamping here)."""
        value = float(value)
        self.send({"type": "slider", "name": slider, "value": value})

        def taken() -> bool:
            now = self._meshcat.GetSliderValue(slider)
            return now == value or (math.isnan(value) and math.isnan(now))

        self._wait(taken, f"the value of {slider!r}")

    def close(self) -> None:
        """Closes the connection (the server sees the browser go)."""
        if self._socket is None:
            return
        sock, self._socket = self._socket, None
        connections = self._meshcat.GetNumActiveConnections()
        try:
            sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        sock.close()
        if self._reader is not None:
            self._reader.join(timeout=_CONNECT_TIMEOUT)
        self._wait(lambda: self._meshcat.GetNumActiveConnections() < connections, "the closing")
