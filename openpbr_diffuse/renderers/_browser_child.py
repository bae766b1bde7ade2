"""Child process: serve a chart scene and a renderer's page on 127.0.0.1, render it in headless
Chromium (playwright), read the float pixels back and write them as an EXR.

    python _browser_child.py PAGE.html SCENE_DIR NODE_MODULES OUT.exr TIMEOUT_S

Run by :mod:`openpbr_diffuse.renderers._browser` under the time limit of user code.  The page
is served at ``/``, the scene folder at ``/scene/``, the npm packages at ``/npm/`` (ES modules
need http, not file://; nothing is fetched from the network).  The page sets
``window.__result`` to ``{data: base64 float32 RGBA rows bottom-up, width, height, version}``
or ``{error: text}``.  The answer (one JSON line on stdout) carries the version.
"""

import base64
import functools
import http.server
import json
import sys
import threading
from pathlib import Path

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--use-gl=angle",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]


def serve(page: Path, scene: Path, node_modules: Path):
    roots = {"/scene/": scene, "/npm/": node_modules}

    class Handler(http.server.SimpleHTTPRequestHandler):
        extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map, ".js": "text/javascript"}

        def translate_path(self, path):
            path = path.split("?", 1)[0].split("#", 1)[0]
            for prefix, root in roots.items():
                if path.startswith(prefix):
                    rel = Path(*[p for p in path[len(prefix) :].split("/") if p not in ("", ".", "..")])
                    return str(root / rel)
            return str(page)

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Handler, directory=str(scene)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def main() -> int:
    page, scene, node_modules, out, timeout = sys.argv[1:6]
    from playwright.sync_api import sync_playwright

    server = serve(Path(page), Path(scene), Path(node_modules))
    url = f"http://127.0.0.1:{server.server_address[1]}/"
    errors = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=sys.argv[6] if len(sys.argv) > 6 else None, args=FLAGS)
        try:
            pg = browser.new_page()
            pg.on("pageerror", lambda e: errors.append(str(e)))
            pg.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            pg.goto(url)
            pg.wait_for_function("window.__result !== undefined", timeout=float(timeout) * 1000)
            result = pg.evaluate("window.__result")
        finally:
            browser.close()
    server.shutdown()
    if "error" in result:
        sys.stderr.write(f"the page failed: {result['error']} {' '.join(errors)[:500]}\n")
        return 3
    import numpy as np
    import OpenImageIO as oiio

    w, h = int(result["width"]), int(result["height"])
    rgba = np.frombuffer(base64.b64decode(result["data"]), "<f4").reshape(h, w, 4)[::-1]  # GL rows are bottom-up
    spec = oiio.ImageSpec(w, h, 3, oiio.FLOAT)
    o = oiio.ImageOutput.create(out)
    if o is None or not o.open(out, spec) or not o.write_image(np.ascontiguousarray(rgba[..., :3])):
        sys.stderr.write(f"cannot write {out}: {oiio.geterror()}\n")
        return 3
    o.close()
    print(json.dumps({"version": result.get("version"), "errors": errors[:5]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
