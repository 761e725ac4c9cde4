"""TCP server for desks: one reader and one writer thread per client.

Each client has a bounded send queue. When its backlog passes
``queue_bytes`` the oldest video frames are dropped first (and a new video
frame is refused); telemetry, events and acks are never dropped — a client
whose backlog of those passes ``max_backlog_bytes`` is disconnected instead,
so one stalled desk never holds up the others.

A peer address may hold at most ``max_per_host`` connections and the server
``max_clients`` in all; a connection beyond either is closed at once and
reported through ``on_reject`` (a peer that opens many connections cannot
starve the desks).
"""

from __future__ import annotations

import logging
import socket
import threading
import time
from collections import deque
from collections.abc import Callable

from app.comm.protocol import DecoderStats, Frame, FrameDecoder, FrameEncoder

log = logging.getLogger(__name__)


class Client:
    def __init__(self, server: TcpServer, sock: socket.socket, addr, cid: int) -> None:
        self.server = server
        self.sock = sock
        self.addr = addr
        self.id = cid
        self.name = f"{addr[0]}:{addr[1]}"
        self.decoder = FrameDecoder()
        self.encoder = FrameEncoder()
        self.enc_lock = threading.Lock()
        self.connected_at = time.monotonic()
        self.last_rx = time.monotonic()
        self.rx_frames = 0
        self.last_heartbeat: tuple[int, float] | None = None  # (peer ts_us, arrival mono)
        self.video_dropped = 0
        self.sent_frames = 0
        self._q: deque[tuple[bool, bytes]] = deque()
        self._q_bytes = 0
        self._cv = threading.Condition()
        self.closed = False
        self._reported_drops = 0
        # who signed this desk's commands (set by the relay after a good command)
        self.desk: str | None = None
        self.session: str | None = None
        self._tokens: float | None = None  # a full bucket at the first command
        self._tokens_t = self.connected_at

    @property
    def label(self) -> str:
        return f"{self.desk} ({self.name})" if self.desk else self.name

    def take_token(self, rate_hz: float, now: float | None = None) -> bool:
        """Token bucket for commands: ``rate_hz`` per second, a burst of as many."""
        now = time.monotonic() if now is None else now
        have = rate_hz if self._tokens is None else self._tokens
        self._tokens = min(rate_hz, have + (now - self._tokens_t) * rate_hz)
        self._tokens_t = now
        if self._tokens >= 1.0:
            self._tokens -= 1.0
            return True
        return False

    # ------------------------------------------------------------------ sending

    def send(self, message, is_video: bool = False) -> None:
        with self.enc_lock:
            data = self.encoder.encode(message)
        self.send_bytes(data, is_video)

    def send_bytes(self, data: bytes, is_video: bool = False) -> None:
        srv = self.server
        with self._cv:
            if self.closed:
                return
            if self._q_bytes + len(data) > srv.queue_bytes:
                self._drop_video()
                if is_video and self._q_bytes + len(data) > srv.queue_bytes:
                    self.video_dropped += 1
                    return
            if self._q_bytes + len(data) > srv.max_backlog_bytes:
                log.warning("client %s is not reading (%d bytes queued); disconnecting",
                            self.name, self._q_bytes)
                self._close_locked()
                return
            self._q.append((is_video, data))
            self._q_bytes += len(data)
            self._cv.notify()

    def _drop_video(self) -> None:
        kept: deque[tuple[bool, bytes]] = deque()
        for item in self._q:
            if item[0] and self._q_bytes > self.server.queue_bytes // 2:
                self._q_bytes -= len(item[1])
                self.video_dropped += 1
            else:
                kept.append(item)
        self._q = kept

    def queued_bytes(self) -> int:
        return self._q_bytes

    def _writer(self) -> None:
        while True:
            with self._cv:
                while not self._q and not self.closed:
                    self._cv.wait()
                if self.closed:
                    return
                _v, data = self._q.popleft()
                self._q_bytes -= len(data)
            try:
                self.sock.sendall(data)
                self.sent_frames += 1
            except OSError as e:
                log.info("client %s send failed: %s", self.name, e)
                self.close()
                return

    # ------------------------------------------------------------------ receiving

    def _reader(self) -> None:
        try:
            while not self.closed:
                try:
                    data = self.sock.recv(65536)
                except OSError:
                    break
                if not data:
                    break
                frames = self.decoder.feed(data)
                now = time.monotonic()
                self.last_rx = now
                for fr in frames:
                    self.rx_frames += 1
                    try:
                        self.server.on_frame(self, fr)
                    except Exception:  # noqa: BLE001 - a handler bug must not kill the link
                        log.exception("error handling %s from %s", fr.msg_type.name, self.name)
                self.server.on_decoder_stats(self, self.decoder.stats)
        finally:
            self.close()

    def close(self) -> None:
        with self._cv:
            self._close_locked()

    def _close_locked(self) -> None:
        if self.closed:
            return
        self.closed = True
        self._q.clear()
        self._q_bytes = 0
        self._cv.notify_all()
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        try:
            self.sock.close()
        except OSError:
            pass
        threading.Thread(target=self.server._gone, args=(self,), daemon=True).start()


class TcpServer:
    def __init__(self, host: str, port: int,
                 on_frame: Callable[[Client, Frame], None],
                 on_connect: Callable[[Client], None] = lambda c: None,
                 on_disconnect: Callable[[Client], None] = lambda c: None,
                 on_decoder_stats: Callable[[Client, DecoderStats], None] = lambda c, s: None,
                 queue_bytes: int = 2_000_000, max_backlog_bytes: int = 16_000_000,
                 max_clients: int = 16, max_per_host: int = 8,
                 on_reject: Callable[[tuple, str], None] = lambda addr, why: None) -> None:
        self.on_frame = on_frame
        self.on_reject = on_reject
        self.max_clients = max_clients
        self.max_per_host = max_per_host
        self.rejected_connections = 0
        self.on_connect = on_connect
        self.on_disconnect = on_disconnect
        self.on_decoder_stats = on_decoder_stats
        self.queue_bytes = queue_bytes
        self.max_backlog_bytes = max_backlog_bytes
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self.sock = socket.create_server((host, port), family=family)
        self.sock.settimeout(0.2)
        self.address = self.sock.getsockname()[:2]
        self._clients: dict[int, Client] = {}
        self._lock = threading.Lock()
        self._next_id = 1
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._accept_loop, name="tcp-accept",
                                        daemon=True)

    def start(self) -> None:
        self._thread.start()

    @property
    def clients(self) -> list[Client]:
        with self._lock:
            return list(self._clients.values())

    def broadcast(self, message, is_video: bool = False) -> None:
        for c in self.clients:
            c.send(message, is_video)

    def _accept_loop(self) -> None:
        while not self._stop.is_set():
            try:
                sock, addr = self.sock.accept()
            except TimeoutError:
                continue
            except OSError:
                break
            with self._lock:
                n_all = len(self._clients)
                n_host = sum(1 for c in self._clients.values() if c.addr[0] == addr[0])
            why = ""
            if n_all >= self.max_clients:
                why = f"{n_all} desks connected (limit {self.max_clients})"
            elif n_host >= self.max_per_host:
                why = f"{n_host} connections from {addr[0]} (limit {self.max_per_host})"
            if why:
                self.rejected_connections += 1
                try:
                    sock.close()
                except OSError:
                    pass
                try:
                    self.on_reject(addr, why)
                except Exception:  # noqa: BLE001 - a handler bug must not stop accepting
                    log.exception("connection reject handler failed")
                continue
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            sock.settimeout(None)
            with self._lock:
                c = Client(self, sock, addr, self._next_id)
                self._next_id += 1
                self._clients[c.id] = c
            log.info("client %s connected", c.name)
            threading.Thread(target=c._writer, name=f"tx-{c.id}", daemon=True).start()
            self.on_connect(c)
            threading.Thread(target=c._reader, name=f"rx-{c.id}", daemon=True).start()

    def _gone(self, c: Client) -> None:
        with self._lock:
            if self._clients.pop(c.id, None) is None:
                return
        log.info("client %s disconnected", c.name)
        self.on_disconnect(c)

    def close(self) -> None:
        self._stop.set()
        try:  # wakes the accept loop at once on Linux (else it waits out its 0.2 s timeout)
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        try:
            self.sock.close()
        except OSError:
            pass
        for c in self.clients:
            c.close()
        if self._thread.is_alive():
            self._thread.join(timeout=2)
