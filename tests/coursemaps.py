"""A loopback HTTP server of the public course maps in ../shared/maps, laid out as their
download URLs expect (``/{repo}/{commit}/{path}``, the path URL-quoted), for
``quadnav maps fetch`` with ``QUADNAV_MAPS_URL`` pointing at it.

The layout comes from the corpus's own ``SOURCES.json``, not from quadnav's catalogue, so a
catalogue entry with a wrong repository, commit or path finds nothing here. The two RBE595
P2b files are members of a zip archive in their repository; the archive's bytes are not in
the corpus, so the server holds a zip built here with the same members.
"""

from __future__ import annotations

import http.server
import io
import json
import threading
import zipfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from urllib.parse import quote


def course_files(shared: Path) -> dict[str, bytes]:
    """URL path -> the bytes served there, for every file of ``shared/SOURCES.json``."""
    files: dict[str, bytes] = {}
    archives: dict[str, dict[str, bytes]] = {}
    for item in json.loads((shared / "SOURCES.json").read_text(encoding="utf-8")):
        url = f"/{item['repo']}/{item['commit']}/{quote(item['path'])}"
        data = (shared / item["file"]).read_bytes()
        if "member" in item:
            archives.setdefault(url, {})[item["member"]] = data
        else:
            files[url] = data
    for url, members in archives.items():
        files[url] = zipped(members)
    return files


def zipped(members: dict[str, bytes]) -> bytes:
    """A zip archive holding ``members`` (path in the archive -> bytes)."""
    archive = io.BytesIO()
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as opened:
        for member, data in members.items():
            opened.writestr(member, data)
    return archive.getvalue()


@contextmanager
def serving(files: dict[str, bytes]) -> Iterator[str]:
    """Serve ``files`` (URL path -> bytes; anything else is a 404) on 127.0.0.1 from a
    thread; yields the base URL, e.g. ``http://127.0.0.1:40123``."""

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            data = files.get(self.path)
            self.send_response(404 if data is None else 200)
            self.send_header("Content-Length", str(len(data or b"")))
            self.end_headers()
            self.wfile.write(data or b"")

        def log_message(self, *args: object) -> None:
            """Quiet: no line per request on stderr."""

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_port}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join()


def dead_url() -> str:
    """The base URL of a loopback port that nothing listens on (connection refused)."""
    with serving({}) as url:
        pass
    return url
