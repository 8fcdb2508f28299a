"""A stand-in OpenAI-compatible chat-completions server for the run benchmark: every request
to POST /v1/chat/completions is read whole and answered after a fixed latency with a
permutation and a `usage` (prompt tokens: 85 per image in the request), so a run's
throughput and memory can be measured without a model. Prints its port on the first line of
standard output, then serves until killed; GET /stats answers the requests counted so far.

    python3 scripts/lib/standin_chat.py [LATENCY_MS]
"""
import json
import sys
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

LATENCY = float(sys.argv[1] if len(sys.argv) > 1 else 200) / 1000.0
COUNT = {"requests": 0, "bytes": 0}
LOCK = threading.Lock()


class Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"  # keep-alive, as a real server would

    def do_POST(self) -> None:
        length = int(self.headers.get("Content-Length", "0"))
        body = self.rfile.read(length)
        images = body.count(b"data:image/png;base64,")
        with LOCK:
            COUNT["requests"] += 1
            COUNT["bytes"] += length
        time.sleep(LATENCY)
        order = list(range(1, max(images, 2)))
        reply = json.dumps(
            {
                "id": "chatcmpl-standin",
                "object": "chat.completion",
                "model": "standin",
                "choices": [
                    {"index": 0, "message": {"role": "assistant", "content": str(order)}, "finish_reason": "stop"}
                ],
                "usage": {"prompt_tokens": 85 * images, "completion_tokens": len(str(order))},
            }
        ).encode()
        self.send_response(200)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(reply)))
        self.end_headers()
        self.wfile.write(reply)

    def do_GET(self) -> None:
        with LOCK:
            reply = json.dumps(COUNT).encode()
        self.send_response(200)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(reply)))
        self.end_headers()
        self.wfile.write(reply)

    def log_message(self, *args: object) -> None:
        pass


class Server(ThreadingHTTPServer):
    daemon_threads = True
    request_queue_size = 256  # 64 connections at once must not overflow the listen backlog


server = Server(("127.0.0.1", 0), Handler)
print(server.server_address[1], flush=True)
server.serve_forever()
