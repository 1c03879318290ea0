"""The simulator's side of the lockstep protocol, played by a thread on a Unix socket, for tests
of the client's run(): it sends the hello and each message, and reads the stack's reply to each."""

import contextlib
import io
import os
import socket
import struct
import tempfile
import threading

from hpa_sim import lockstep


def _read(conn, n):
    """Exactly n bytes from conn; EOFError if it closes first."""
    data = b""
    while len(data) < n:
        chunk = conn.recv(n - len(data))
        if not chunk:
            raise EOFError
        data += chunk
    return data


def serve(controller_class, hello, messages, **run_options):
    """Runs lockstep.run(controller_class, **run_options) against a simulator that sends `hello`
    then each of `messages` ((type, body) pairs), one per reply, and stops after an error message
    or when the stack closes. Returns run()'s exit code and the replies, a list of (type, body)."""
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "lockstep.sock")
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as server:
            server.bind(path)
            server.listen(1)
            replies = []

            def simulator():
                conn, _ = server.accept()
                with conn:
                    try:
                        for kind, body in [(lockstep.HELLO, hello)] + list(messages):
                            try:
                                header = struct.pack("<III", lockstep.MAGIC, kind, len(body))
                                conn.sendall(header + body)
                            except OSError:  # the stack sent its error and closed: read it
                                pass
                            _, reply_kind, length = struct.unpack("<III", _read(conn, 12))
                            replies.append((reply_kind, _read(conn, length)))
                            if reply_kind == lockstep.ERROR:
                                return
                    except (EOFError, OSError):
                        pass

            thread = threading.Thread(target=simulator)
            thread.start()
            old = os.environ.get("HPA_FLIGHT_SOCKET")
            os.environ["HPA_FLIGHT_SOCKET"] = path
            try:
                with contextlib.redirect_stderr(io.StringIO()):
                    code = lockstep.run(controller_class, name="test", **run_options)
            finally:
                if old is None:
                    del os.environ["HPA_FLIGHT_SOCKET"]
                else:
                    os.environ["HPA_FLIGHT_SOCKET"] = old
                thread.join(10)
    return code, replies
