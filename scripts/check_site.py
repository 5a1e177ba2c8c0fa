#!/usr/bin/env python3
"""Walks a static site in headless Chromium, as a reader's browser would (issue 44):

    scripts/check_site.py SITE_DIR [--browser PATH] [--expect-text TEXT] [--json OUT]

Every `.html` file under SITE_DIR is loaded from the file system (file://). On each page:

- console errors: console.error/assert calls, uncaught exceptions, and the browser's own
  error log entries (a resource that failed to load is one);
- every resource a page embeds (scripts, styles, frames, `<object>` charts): a file of the site;
- every image: loaded eagerly (`loading=lazy` is lifted so that every one is fetched), and
  counted missing when it failed or has no pixels; images must be files of the site;
- every link: a file of the site (with its `#anchor`, which must exist in the target page);
  links outside the site (http…) are counted as external and fail the check, since the site
  must work with no network;
- live markup: any element carrying an `on…` handler attribute, a dialog (alert) opening, or
  an element `img[src=x]` means a name's markup ran as a tag;
- with --expect-text, TEXT must be a page's visible text somewhere (the name stays text).

Every page must be reachable by links from index.html. With --only GLOB (repeatable) only the
matching pages are walked (for a site of a thousand runs: index.html and the histories). Prints a JSON summary (pages, links,
images, and the lists of problems) and exits 1 when there is any problem.

The browser is driven through the Chrome DevTools Protocol over a pipe
(`--remote-debugging-pipe`: JSON messages separated by NUL on file descriptors 3 and 4), so
nothing beyond Python's standard library and the browser is needed.
"""

import argparse
import fnmatch
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.parse
from pathlib import Path


class Browser:
    def __init__(self, binary):
        self.profile = tempfile.mkdtemp(prefix="check-site-")
        to_browser_r, self.to_browser = os.pipe()
        self.from_browser, from_browser_w = os.pipe()

        def wire():
            os.dup2(to_browser_r, 3)
            os.dup2(from_browser_w, 4)

        args = [binary, "--headless", "--remote-debugging-pipe", "--disable-gpu",
                "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--no-first-run", "--hide-scrollbars",
                "--allow-file-access-from-files", f"--user-data-dir={self.profile}",
                "--window-size=1400,1000"]
        if os.geteuid() == 0:
            args.append("--no-sandbox")
        self.proc = subprocess.Popen(args, preexec_fn=wire, pass_fds=(3, 4),
                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.buffer = b""
        self.next_id = 0
        self.events = []
        self.dialogs = []

    def close(self):
        try:
            self.send("Browser.close", timeout=10)
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        os.close(self.to_browser)
        os.close(self.from_browser)
        shutil.rmtree(self.profile, ignore_errors=True)

    def _read_message(self, deadline):
        while b"\0" not in self.buffer:
            if time.monotonic() > deadline:
                raise TimeoutError("the browser did not answer in time")
            import select
            ready, _, _ = select.select([self.from_browser], [], [], 0.5)
            if ready:
                chunk = os.read(self.from_browser, 1 << 20)
                if not chunk:
                    raise RuntimeError("the browser closed its pipe (did it crash?)")
                self.buffer += chunk
        msg, self.buffer = self.buffer.split(b"\0", 1)
        msg = json.loads(msg)
        if msg.get("method") == "Page.javascriptDialogOpening":
            # A dialog (alert) blocks the page until answered: note it, dismiss it at once.
            self.dialogs.append((msg.get("sessionId"), msg["params"].get("message")))
            self.next_id += 1
            os.write(self.to_browser, json.dumps({
                "id": self.next_id, "sessionId": msg.get("sessionId"),
                "method": "Page.handleJavaScriptDialog", "params": {"accept": True}}).encode() + b"\0")
        return msg

    def send(self, method, params=None, session=None, timeout=60):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.to_browser, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            m = self._read_message(deadline)
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self.events.append(m)

    def wait_event(self, method, session, timeout=60):
        deadline = time.monotonic() + timeout
        while True:
            for i, e in enumerate(self.events):
                if e.get("method") == method and e.get("sessionId") == session:
                    return self.events.pop(i)
            self.events.append(self._read_message(deadline))

    def drain(self, seconds):
        deadline = time.monotonic() + seconds
        while True:
            try:
                self.events.append(self._read_message(deadline))
            except TimeoutError:
                return


PAGE_CHECK = r"""
(async () => {
  for (const img of document.images) { img.loading = "eager"; }
  const t0 = Date.now();
  while (Date.now() - t0 < 15000 && !Array.from(document.images).every(i => i.complete)) {
    await new Promise(r => setTimeout(r, 50));
  }
  await Promise.all(Array.from(document.images).map(i => i.decode().catch(() => null)));
  const handlers = Array.from(document.querySelectorAll("*")).filter(
    e => Array.from(e.attributes).some(a => a.name.toLowerCase().startsWith("on"))).length;
  return JSON.stringify({
    images: Array.from(document.images).map(i => ({
      src: i.src, ok: i.complete && i.naturalWidth > 0 })),
    resources: Array.from(document.querySelectorAll("script[src],link[href],source[src],iframe[src],object[data]"))
      .map(e => e.src || e.href || e.data),
    links: Array.from(document.querySelectorAll("a[href]")).map(a => a.href),
    ids: Array.from(document.querySelectorAll("[id],a[name]")).map(e => e.id || e.name),
    handlers: handlers,
    injected: document.querySelectorAll('img[src="x"]').length,
    text: document.body ? document.body.innerText : "",
    title: document.title,
  });
})()
"""


def file_of(url):
    """The local path of a file:// URL (without its fragment), or None."""
    parsed = urllib.parse.urlparse(url)
    if parsed.scheme != "file":
        return None
    return Path(urllib.parse.unquote(parsed.path))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("site")
    ap.add_argument("--browser", default=shutil.which("chromium") or shutil.which("chromium-browser")
                    or shutil.which("google-chrome"))
    ap.add_argument("--expect-text", action="append", default=[])
    ap.add_argument("--json")
    ap.add_argument("--only", action="append", default=[], metavar="GLOB",
                    help="walk only the pages whose path in the site matches GLOB (fnmatch; "
                         "repeatable), for a site too large to walk whole: links to other "
                         "pages must still name files of the site, their anchors are not checked")
    a = ap.parse_args()
    if not a.browser:
        sys.exit("check_site: no Chromium (chromium, chromium-browser, google-chrome) on PATH")
    site = Path(a.site).resolve()
    pages = sorted(site.rglob("*.html"))
    if a.only:
        pages = [p for p in pages
                 if any(fnmatch.fnmatch(p.relative_to(site).as_posix(), g) for g in a.only)]
    if not (site / "index.html").is_file():
        sys.exit(f"check_site: {site}/index.html does not exist")

    problems = {"console_errors": [], "missing_images": [], "broken_links": [],
                "external": [], "live_markup": [], "unreachable_pages": [],
                "missing_text": []}
    linked = {site / "index.html"}
    anchors = []  # (page, target file, fragment)
    ids_of = {}
    texts = {}
    counts = {"pages": 0, "links": 0, "images": 0}

    browser = Browser(a.browser)
    try:
        target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = browser.send("Target.attachToTarget",
                               {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log", "Network"):
            browser.send(f"{domain}.enable", session=session)
        for page in pages:
            rel = page.relative_to(site).as_posix()
            browser.events = [e for e in browser.events if e.get("sessionId") != session]
            browser.send("Page.navigate", {"url": page.as_uri()}, session=session)
            browser.wait_event("Page.loadEventFired", session, timeout=60)
            result = browser.send("Runtime.evaluate",
                                  {"expression": PAGE_CHECK, "awaitPromise": True,
                                   "returnByValue": True}, session=session, timeout=60)
            if "exceptionDetails" in result:
                problems["console_errors"].append(f"{rel}: the check script failed: "
                                                  f"{result['exceptionDetails']}")
                continue
            info = json.loads(result["result"]["value"])
            browser.drain(0.3)
            counts["pages"] += 1
            for e in browser.events:
                if e.get("sessionId") != session:
                    continue
                m, p = e.get("method"), e.get("params", {})
                if m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                    args = " ".join(str(x.get("value", x.get("description", ""))) for x in p.get("args", []))
                    problems["console_errors"].append(f"{rel}: console.{p['type']}: {args}")
                elif m == "Runtime.exceptionThrown":
                    d = p.get("exceptionDetails", {})
                    problems["console_errors"].append(
                        f"{rel}: exception: {d.get('exception', {}).get('description', d.get('text'))}")
                elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
                    entry = p["entry"]
                    problems["console_errors"].append(
                        f"{rel}: {entry.get('source')}: {entry.get('text')} {entry.get('url', '')}".strip())
                elif m == "Network.loadingFailed" and not p.get("canceled"):
                    problems["console_errors"].append(
                        f"{rel}: failed to load ({p.get('errorText')})")
            browser.events = [e for e in browser.events if e.get("sessionId") != session]
            for _, message in browser.dialogs:
                problems["live_markup"].append(f"{rel}: a dialog opened: {message}")
            browser.dialogs = []
            if info["handlers"] or info["injected"]:
                problems["live_markup"].append(
                    f"{rel}: {info['handlers']} element(s) with an on… handler, "
                    f"{info['injected']} injected img[src=x]")
            ids_of[page] = set(info["ids"])
            texts[rel] = info["text"]
            for img in info["images"]:
                counts["images"] += 1
                path = file_of(img["src"])
                if path is None:
                    problems["external"].append(f"{rel}: image {img['src']}")
                elif not img["ok"] or not path.is_file() or site not in path.parents:
                    problems["missing_images"].append(f"{rel}: {img['src']}")
            for url in info["resources"]:
                path = file_of(url)
                if path is None:
                    problems["external"].append(f"{rel}: resource {url}")
                elif not path.is_file():
                    problems["broken_links"].append(f"{rel}: resource {url}")
            for url in info["links"]:
                counts["links"] += 1
                path = file_of(url)
                if path is None:
                    problems["external"].append(f"{rel}: link {url}")
                    continue
                fragment = urllib.parse.urlparse(url).fragment
                if path.is_dir():
                    path = path / "index.html"
                if not path.is_file() or site not in path.parents:
                    problems["broken_links"].append(f"{rel}: {url}")
                    continue
                if path.suffix == ".html":
                    linked.add(path)
                    if fragment:
                        anchors.append((rel, path, urllib.parse.unquote(fragment)))
    finally:
        browser.close()

    for rel, path, fragment in anchors:
        if a.only and path not in ids_of:
            continue  # a page outside --only: not walked
        if fragment not in ids_of.get(path, set()):
            problems["broken_links"].append(f"{rel}: #{fragment} is not an anchor of "
                                            f"{path.relative_to(site).as_posix()}")
    for page in pages:
        if page not in linked:
            problems["unreachable_pages"].append(page.relative_to(site).as_posix())
    for text in a.expect_text:
        if not any(text in t for t in texts.values()):
            problems["missing_text"].append(f"no page shows {text!r} as text")

    summary = dict(counts, **problems)
    out = json.dumps(summary, indent=2)
    if a.json:
        Path(a.json).write_text(out + "\n")
    print(out)
    bad = sum(len(v) for v in problems.values())
    print(f"check_site: {counts['pages']} pages, {counts['links']} links, {counts['images']} "
          f"images; {bad} problem(s)", file=sys.stderr)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
