"""report.html: one self-contained page (no network: a Content-Security-Policy allows only
inline styles, one inline script and data: images), rendered from the same text as report.md
so the two can never disagree, with the figures embedded as SVG (vector: they stay sharp at
any zoom).

Every figure pans and zooms in place (a small inline script, :data:`_SCRIPT`): the mouse wheel
zooms about the pointer (1x to 40x), dragging pans, a double click or "reset" returns to the
whole figure, and "+" / "-" zoom about the centre (keyboard or touchpad without a wheel).
"full window" opens a figure over the whole window (a CSS ``:target`` overlay; "close" or the
browser's back button closes it), where it pans and zooms the same way. Without script the
figures are still shown whole.

Only the small subset of Markdown that :func:`~zrp.gap.report.markdown.report_markdown`
writes is translated: headings, paragraphs, ``- `` lists, pipe tables, ``**bold**``,
```code``` and ``![alt](file.png)`` figures (scatter points are rasterised inside the SVG).
Backslash escapes (:func:`zrp.escape.md_text`, on every user string) are honoured as CommonMark
does: an escaped character is shown as text, never as bold, code, a cell or a tag.
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Callable, Mapping

__all__ = ["report_html"]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;max-width:1100px;
margin:1.5em auto;padding:0 1em;color:#1b1b1b;line-height:1.45}
h1{font-size:1.5em;margin-bottom:.2em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;
margin-top:1.6em}
#verdict{background:#fff4d6;border-left:6px solid #d08c00;padding:.8em 1.1em;font-size:1.08em}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em}
td,th{border:1px solid #ccc;padding:.25em .5em;text-align:left;vertical-align:top}
th{background:#f0f0f0}tr:nth-child(even) td{background:#fafafa}
code{background:#f2f2f2;padding:0 .2em}
figure{margin:1em 0}figcaption{font-size:.85em;color:#555}
.pz{overflow:hidden;border:1px solid #ddd;cursor:grab;touch-action:none;background:#fff;
display:inline-block;max-width:100%;line-height:0}
.pz img{display:block;max-width:100%;transform-origin:0 0;user-select:none;
-webkit-user-drag:none}
.tools{font-size:.85em;margin:.2em 0}.tools button,.tools a{margin-right:.4em}
figure:target{position:fixed;inset:0;margin:0;background:rgba(0,0,0,.85);z-index:10;
display:flex;flex-direction:column;align-items:center;justify-content:center}
figure:target .pz img{max-width:98vw;max-height:88vh}
figure .close{display:none}figure:target .close{display:inline;color:#fff}
figure:target .full{display:none}figure:target figcaption{color:#eee}
"""

#: pan and zoom of every ``.pz`` box (see the module docstring); the state is mirrored into
#: the box's data-scale / data-tx / data-ty attributes (read by the browser test).
_SCRIPT = """(function(){
document.querySelectorAll('figure').forEach(function(fig){
var box=fig.querySelector('.pz'),img=box.querySelector('img'),s=1,x=0,y=0,drag=null;
function apply(){img.style.transform='translate('+x+'px,'+y+'px) scale('+s+')';
box.dataset.scale=s.toFixed(4);box.dataset.tx=x.toFixed(1);box.dataset.ty=y.toFixed(1);}
function zoom(f,cx,cy){var n=Math.min(40,Math.max(1,s*f));f=n/s;x=cx-(cx-x)*f;
y=cy-(cy-y)*f;s=n;if(s===1){x=0;y=0;}apply();}
function centre(f){var r=box.getBoundingClientRect();zoom(f,r.width/2,r.height/2);}
box.addEventListener('wheel',function(e){e.preventDefault();
var r=box.getBoundingClientRect();zoom(Math.exp(-e.deltaY*0.0015),e.clientX-r.left,
e.clientY-r.top);},{passive:false});
box.addEventListener('pointerdown',function(e){drag={x:e.clientX-x,y:e.clientY-y};
box.style.cursor='grabbing';});
box.addEventListener('pointermove',function(e){if(!drag||s===1)return;
x=e.clientX-drag.x;y=e.clientY-drag.y;apply();});
function up(){drag=null;box.style.cursor='';}
box.addEventListener('pointerup',up);box.addEventListener('pointerleave',up);
box.addEventListener('pointercancel',up);
box.addEventListener('dblclick',function(){s=1;x=0;y=0;apply();});
fig.querySelector('.zin').addEventListener('click',function(){centre(1.5);});
fig.querySelector('.zout').addEventListener('click',function(){centre(1/1.5);});
fig.querySelector('.zreset').addEventListener('click',function(){s=1;x=0;y=0;apply();});
apply();});})();"""

#: no network: only inline style, the inline script and data: images.
_CSP = ("default-src 'none'; img-src data:; style-src 'unsafe-inline'; "
        "script-src 'unsafe-inline'")


_ESCAPED = re.compile(r"\\([!-/:-@\[-`{-~])")
_HELD = re.compile("\x00(\\d+)\x00")
#: a cell boundary: a pipe not escaped by a backslash
_CELL = re.compile(r"(?<!\\)\|")


def _inline(text: str) -> str:
    held: list[str] = []

    def hold(m: re.Match[str]) -> str:  # an escaped character: text, whatever follows
        held.append(html.escape(m.group(1)))
        return f"\x00{len(held) - 1}\x00"

    t = html.escape(_ESCAPED.sub(hold, text.replace("\x00", "")), quote=False)
    t = re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", t)
    t = re.sub(r"`([^`]+)`", r"<code>\1</code>", t)
    return _HELD.sub(lambda m: held[int(m.group(1))], t)


def _table(rows: list[str]) -> str:
    cells = [[c.strip() for c in _CELL.split(r.strip().strip("|"))] for r in rows]
    head, body = cells[0], [c for c in cells[1:] if not all(set(x) <= {"-", ":"} for x in c)]
    out = ["<table><thead><tr>" + "".join(f"<th>{_inline(c)}</th>" for c in head)
           + "</tr></thead><tbody>"]
    out += ["<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r) + "</tr>" for r in body]
    return "\n".join(out) + "</tbody></table>"


def _figure(alt: str, name: str, svgs: Mapping[str, bytes]) -> str:
    svg = svgs.get(name)
    if svg is None:
        return ""
    src = "data:image/svg+xml;base64," + base64.b64encode(svg).decode("ascii")
    fid = "zoom-" + re.sub(r"[^a-z0-9]+", "-", name.lower())
    return (f'<figure id="{fid}"><div class="tools"><button type="button" class="zin" '
            'title="zoom in">+</button><button type="button" class="zout" title="zoom out">'
            '-</button><button type="button" class="zreset">reset</button>'
            f'<a class="full" href="#{fid}">full window</a><a class="close" href="#_">'
            f'close x</a></div><div class="pz"><img src="{src}" alt="{html.escape(alt)}" '
            f'draggable="false"></div><figcaption>{html.escape(alt)} (wheel: zoom, drag: pan, '
            f"double click: whole figure; {html.escape(name)} beside this file)</figcaption>"
            "</figure>")


def _run_end(lines: list[str], i: int, keep: Callable[[str], bool]) -> int:
    """The first line from ``i`` on that ``keep`` rejects (or the end)."""
    while i < len(lines) and keep(lines[i]):
        i += 1
    return i


def _verdict(lines: list[str], i: int) -> tuple[str, int]:
    """The verdict's headline: the first paragraph from ``i`` (its lines up to a blank line
    or a heading, as one); the table and the detail sections after it are ordinary blocks."""
    i = _run_end(lines, i, lambda s: not s.strip())
    j = _run_end(lines, i, lambda s: bool(s.strip()) and not s.startswith(("#", "|")))
    return f'<div id="verdict">{_inline(" ".join(lines[i:j]))}</div>', j


def _block(lines: list[str], i: int, svgs: Mapping[str, bytes]) -> tuple[str, int]:
    """The HTML of the block (table, figure, list or paragraph) at line ``i`` and the line
    after it."""
    ln = lines[i]
    if ln.startswith("|"):
        j = _run_end(lines, i, lambda s: s.startswith("|"))
        return _table(lines[i:j]), j
    fm = re.match(r"^!\[(.*)\]\((.*)\)\s*$", ln)
    if fm:
        return _figure(fm.group(1), fm.group(2), svgs), i + 1
    if ln.lstrip().startswith("- "):
        j = _run_end(lines, i, lambda s: s.lstrip().startswith("- "))
        items = "".join(f"<li>{_inline(s.lstrip()[2:])}</li>" for s in lines[i:j])
        return "<ul>" + items + "</ul>", j
    return f"<p>{_inline(ln)}</p>", i + 1


def _blocks(md: str, svgs: Mapping[str, bytes]) -> list[str]:
    out: list[str] = []
    lines = md.splitlines()
    i, verdict_done = 0, False
    while i < len(lines):
        m = re.match(r"^(#{1,3}) (.*)$", lines[i])
        if not lines[i].strip():
            i += 1
        elif m is None:
            block, i = _block(lines, i, svgs)
            out.append(block)
        else:
            lvl = len(m.group(1))
            out.append(f"<h{lvl}>{_inline(m.group(2))}</h{lvl}>")
            i += 1
            if lvl == 2 and not verdict_done and m.group(2).strip() == "Verdict":
                verdict_done = True
                block, i = _verdict(lines, i)
                out.append(block)
    return out


def report_html(markdown: str, svgs: Mapping[str, bytes], title: str) -> str:
    """The page for the text of report.md and the figures as SVG (keyed by their PNG file
    names, as report.md references them)."""
    body = "\n".join(_blocks(markdown, svgs))
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<meta http-equiv=\"Content-Security-Policy\" content=\"{_CSP}\">"
            "<link rel=\"icon\" href=\"data:,\">"
            f"<title>{html.escape(title)}</title><style>{_CSS}</style></head>"
            f"<body>\n{body}\n<script>{_SCRIPT}</script>\n</body></html>\n")
