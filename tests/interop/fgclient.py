"""A minimal Foxglove WebSocket client for tests and the bench (the ``websockets``
package's threading client): reads the server's advertisements, subscribes to topics,
and collects message data frames as (topic, log time ns, receive time s, payload)."""

from __future__ import annotations

import json
import struct
import threading
import time

from websockets.sync.client import connect

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
MESSAGE_DATA = 0x01


class Client:
    def __init__(self, port: int, topics: list[str]) -> None:
        self.ws = connect(f"ws://127.0.0.1:{port}", subprotocols=SUBPROTOCOLS, legacy=True,
                          open_timeout=5, max_size=None)
        self.want = set(topics)
        self.channels: dict[int, dict] = {}   # channel id -> advertisement
        self.subs: dict[int, str] = {}        # subscription id -> topic
        self.messages: list[tuple[str, int, float, bytes]] = []
        self.server_info: dict = {}
        self._lock = threading.Lock()
        self._stop = False
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop:
            try:
                frame = self.ws.recv(timeout=0.2)
            except TimeoutError:
                continue
            except Exception:  # closed
                return
            now = time.time()
            if isinstance(frame, bytes):
                if frame[0] == MESSAGE_DATA:
                    sub, log_ns = struct.unpack_from("<IQ", frame, 1)
                    with self._lock:
                        self.messages.append((self.subs.get(sub, "?"), log_ns, now,
                                              frame[13:]))
                continue
            msg = json.loads(frame)
            if msg.get("op") == "serverInfo":
                self.server_info = msg
            elif msg.get("op") == "advertise":
                new = []
                for ch in msg["channels"]:
                    self.channels[ch["id"]] = ch
                    if ch["topic"] in self.want:
                        sid = len(self.subs) + 1
                        self.subs[sid] = ch["topic"]
                        new.append({"id": sid, "channelId": ch["id"]})
                if new:
                    self.ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))

    def subscribed(self) -> set[str]:
        return set(self.subs.values())

    def of(self, topic: str) -> list[tuple[str, int, float, bytes]]:
        with self._lock:
            return [m for m in self.messages if m[0] == topic]

    def close(self) -> None:
        self._stop = True
        self.ws.close()
        self._thread.join(timeout=2)
