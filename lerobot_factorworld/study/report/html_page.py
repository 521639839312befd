"""The page ``report.html`` is written into (``html_report.py``): a small template, its style and the paired-episode
viewer's script, all inline so the page opens from disk with nothing but ``plotly.min.js`` next to it."""

from __future__ import annotations

PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>{style}</style>
<script src="{plotly_js}"></script>
</head>
<body>
<header>
<h1>{title}</h1>
<p class="lead">{lead}</p>
<p id="plotly-missing" class="note" hidden>The figures need <code>{plotly_js}</code> next to this file:
<code>factorworld report --results=results.csv</code> in this folder writes it.</p>
<nav>{nav}</nav>
</header>
<main>
{sections}
</main>
<script>if (!window.Plotly) document.getElementById("plotly-missing").hidden = false;</script>
{viewer_data}
<script>{viewer_js}</script>
</body>
</html>
"""

STYLE = """
body { font: 15px/1.45 system-ui, sans-serif; margin: 0; color: #1d2330; background: #fafbfc; }
header, main { max-width: 1180px; margin: 0 auto; padding: 0 20px; }
header { padding-top: 12px; }
h1 { font-size: 1.6em; margin: 0.4em 0 0.2em; }
h2 { font-size: 1.25em; margin: 1.6em 0 0.4em; border-bottom: 1px solid #d8dde6; padding-bottom: 4px; }
nav a { margin-right: 14px; }
.lead, .note, figcaption { color: #4a5263; }
.note { font-size: 0.92em; }
figure { margin: 0.6em 0 1em; }
table { border-collapse: collapse; margin: 0.6em 0 1em; font-size: 0.9em; }
th, td { border: 1px solid #d8dde6; padding: 3px 8px; text-align: left; vertical-align: top; }
th { background: #eef1f5; }
td.num { font-variant-numeric: tabular-nums; }
.verdict { font-weight: 600; padding: 1px 6px; border-radius: 4px; white-space: nowrap; }
.verdict.agrees { background: #d7f0dc; color: #135c22; }
.verdict.disagrees { background: #f8d9d6; color: #8a1c12; }
.verdict.not-resolved { background: #eceff3; color: #3b4250; }
.verdict.capped { background: #fbeccb; color: #7a4d00; }
.verdict.confounded { background: #f3e0f5; color: #5e1a6b; }
.viewer-controls { display: flex; flex-wrap: wrap; gap: 10px 18px; align-items: center; margin: 0.6em 0; }
.viewer-controls label { display: inline-flex; gap: 6px; align-items: center; }
.pair { display: flex; flex-wrap: wrap; gap: 20px; }
.pair figure { margin: 0; }
.pair video { width: 336px; height: 336px; image-rendering: pixelated; background: #000; display: block; }
.episode-label { font-size: 0.9em; margin-top: 4px; max-width: 336px; }
.success { color: #135c22; font-weight: 600; }
.failure { color: #8a1c12; font-weight: 600; }
.transport { display: flex; gap: 10px; align-items: center; margin: 10px 0; }
.transport input[type=range] { width: 420px; }
code { background: #eef1f5; padding: 0 3px; border-radius: 3px; }
"""

VIEWER_HTML = """<p class="note">Episode <i>i</i> under <code>train</code> and under the chosen shift start the object
at the same place (the same reset seed). One clock drives both videos; the shorter one (an episode ends at success) holds
its last frame until the longer one ends, then both start again.</p>
<div id="viewer">
<div class="viewer-controls">
<label id="v-cell-label">checkpoint <select id="v-cell"></select></label>
<label>shift <select id="v-condition"></select></label>
<button id="v-prev" type="button">&larr; previous</button>
<span id="v-index"></span>
<button id="v-next" type="button">next &rarr;</button>
</div>
<div class="pair">
<figure><video id="v-left" muted playsinline preload="auto"></video>
<figcaption id="v-left-label" class="episode-label"></figcaption></figure>
<figure><video id="v-right" muted playsinline preload="auto"></video>
<figcaption id="v-right-label" class="episode-label"></figcaption></figure>
</div>
<div class="transport">
<button id="v-play" type="button">Play</button>
<input id="v-seek" type="range" min="0" max="1000" value="0" aria-label="time">
<span id="v-time"></span>
</div>
</div>
<p id="viewer-unpaired" class="note" hidden>The recorded episodes have no <code>train</code> episode to pair
with: record the <code>train</code> condition too.</p>"""

# The paired-episode viewer: episode i of `train` and of the chosen shift, side by side, one clock for both. The
# longer video leads; the shorter one holds its last frame once it ends (an episode ends at success), and both
# start again together when the longer one ends.
VIEWER_JS = r"""
(function () {
  const source = document.getElementById("episodes-data");
  if (!source) return;
  const entries = JSON.parse(source.textContent);
  const CELL = ["method", "task", "n_train_envs", "seed", "widths"];
  const cellKey = (e) => CELL.map((k) => String(e[k])).join(" | ");
  const cellName = (e) =>
    `${e.method} · ${e.task} · N=${e.n_train_envs} · seed ${e.seed}` +
    (e.widths === "default" ? "" : ` · widths ${e.widths}`);
  const cells = new Map();  // cell -> condition -> index -> entry
  const names = new Map();
  for (const e of entries) {
    const key = cellKey(e);
    names.set(key, cellName(e));
    if (!cells.has(key)) cells.set(key, new Map());
    const byCondition = cells.get(key);
    if (!byCondition.has(e.condition)) byCondition.set(e.condition, new Map());
    byCondition.get(e.condition).set(e.index, e);
  }
  const $ = (id) => document.getElementById(id);
  const cellSelect = $("v-cell"), conditionSelect = $("v-condition");
  const left = $("v-left"), right = $("v-right");
  const videos = [left, right];
  let indices = [], at = 0, playing = false;

  function option(select, value, text) {
    const o = document.createElement("option");
    o.value = value; o.textContent = text; select.appendChild(o);
  }
  function pairedCells() {
    return [...cells.keys()].filter((key) => shifts(key).length > 0);
  }
  function shifts(key) {
    const byCondition = cells.get(key);
    if (!byCondition.has("train")) return [];
    return [...byCondition.keys()].filter((c) => c !== "train" && pairs(key, c).length > 0);
  }
  function pairs(key, condition) {
    const byCondition = cells.get(key);
    const train = byCondition.get("train");
    return [...byCondition.get(condition).keys()].filter((i) => train.has(i)).sort((a, b) => a - b);
  }
  function fillConditions() {
    const keep = conditionSelect.value;
    conditionSelect.replaceChildren();
    for (const c of shifts(cellSelect.value)) option(conditionSelect, c, c);
    if ([...conditionSelect.options].some((o) => o.value === keep)) conditionSelect.value = keep;
  }
  function label(target, e) {
    target.replaceChildren();
    const head = document.createElement("strong");
    head.textContent = e.condition;
    const outcome = document.createElement("span");
    outcome.className = e.success ? "success" : "failure";
    outcome.textContent = e.success ? "success" : "failure";
    const rest = document.createElement("span");
    const stage = e.stage ?? "not recorded", steps = e.length ?? "?";
    rest.textContent = ` · furthest stage: ${stage} · ${steps} steps · reset seed ${e.episode_seed}`;
    target.append(head, " · ", outcome, rest);
    target.dataset.success = String(e.success);
    target.dataset.stage = String(e.stage);
  }
  function show() {
    const key = cellSelect.value, condition = conditionSelect.value;
    indices = pairs(key, condition);
    at = Math.min(at, indices.length - 1);
    const i = indices[at];
    const byCondition = cells.get(key);
    const a = byCondition.get("train").get(i), b = byCondition.get(condition).get(i);
    pause();
    left.src = a.video; right.src = b.video;
    left.dataset.entry = `${key} | train | ${i}`; right.dataset.entry = `${key} | ${condition} | ${i}`;
    label($("v-left-label"), a); label($("v-right-label"), b);
    $("v-index").textContent = `episode ${i} (${at + 1} of ${indices.length})`;
    $("v-prev").disabled = at <= 0; $("v-next").disabled = at >= indices.length - 1;
    $("v-seek").value = 0;
  }
  const duration = (v) => (Number.isFinite(v.duration) ? v.duration : 0);
  const leader = () => (duration(right) > duration(left) ? right : left);
  function setTime(t) {
    for (const v of videos) v.currentTime = Math.max(0, Math.min(t, duration(v) - 0.001));
  }
  function play() {
    playing = true;
    $("v-play").textContent = "Pause";
    const t = leader().currentTime;
    for (const v of videos) if (t < duration(v)) v.play().catch(() => {});
    requestAnimationFrame(tick);
  }
  function pause() {
    playing = false;
    $("v-play").textContent = "Play";
    for (const v of videos) v.pause();
  }
  function tick() {
    const lead = leader(), other = lead === left ? right : left;
    const t = lead.currentTime;
    if (playing && t < duration(other)) {
      if (Math.abs(other.currentTime - t) > 0.05) other.currentTime = t;
      if (other.paused && !lead.paused) other.play().catch(() => {});
    }
    const total = duration(lead);
    if (total > 0) $("v-seek").value = Math.round((1000 * t) / total);
    $("v-time").textContent = `${t.toFixed(2)} / ${total.toFixed(2)} s`;
    if (playing) requestAnimationFrame(tick);
  }
  for (const v of videos) {
    v.loop = false;
    v.addEventListener("ended", () => {
      if (playing && v === leader()) { setTime(0); play(); }
    });
    v.addEventListener("loadedmetadata", tick);
  }
  $("v-play").addEventListener("click", () => (playing ? pause() : play()));
  $("v-seek").addEventListener("input", (event) => {
    setTime((Number(event.target.value) / 1000) * duration(leader()));
    tick();
  });
  $("v-prev").addEventListener("click", () => { at -= 1; show(); });
  $("v-next").addEventListener("click", () => { at += 1; show(); });
  cellSelect.addEventListener("change", () => { fillConditions(); at = 0; show(); });
  conditionSelect.addEventListener("change", () => { at = 0; show(); });

  const usable = pairedCells();
  if (!usable.length) {
    $("viewer").hidden = true;
    $("viewer-unpaired").hidden = false;
    return;
  }
  for (const key of usable) option(cellSelect, key, names.get(key));
  $("v-cell-label").hidden = usable.length < 2;
  fillConditions();
  show();
  window.episodeViewer = { show, play, pause, setTime, entries };
})();
"""
