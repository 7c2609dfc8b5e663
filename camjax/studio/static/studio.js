// camjax studio: the page.  The program lives here as its structure (`model`, as the TOML
// reader gives it); every edit posts it as JSON (debounced) and the server, which alone
// reads and writes TOML, answers the report of `camjax program --format json`, or the
// library's one-line error, shown beside the field edited last while the last good state
// stays drawn.  The fields, the follower's kinds and which segments carry a residual
// vibration come from the server (GET /api/program's `fields`, the report), not from here.
"use strict";

const SESSION = (crypto.randomUUID ? crypto.randomUUID() : String(Math.random()).slice(2));
const END_KEYS = ["velocity_mm_per_deg", "acceleration_mm_per_deg2", "jerk_mm_per_deg3"];
const NUMBER = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/;

let model = null;        // {program: {name}, segment: [...], follower: {...}, materials?: {...}}
let bundle = false;      // the program holds a designed law: saved as a zip with its law files
let designDefaults = {steps: 60};   // the server's (GET /api/program)
let followerDefaults = {};          // what an empty follower field stands for (GET /api/program)
let fields = {follower: [], follower_kinds: [], body: [], spring: [], seat: [], chain_replaces: [], arm: []};  // the server's
const dwellLift = new WeakMap();    // a segment's lift while it is a dwell, restored with a law
let rollerCleared = false;
let errorFrom = null;               // what the standing error came from: "program" or "chosen" (the speed)
let polling = null;      // the design's progress timer
let laws = [];
let rpmText = "";
let chosen = null;       // the chosen speed (null: the server's choice)
let report = null;       // last good report
let curves = null;       // last good curves
let lastField = null;    // the input edited last (where an error is shown)
let opened = false;      // the program came from "Open TOML": files it names relative to itself cannot be read
let timer = null, inFlight = false, dirty = false;
const charts = {};

const $ = (id) => document.getElementById(id);
// A follower kind's record from the server's list (camjax.program.follower_kinds); the
// default kind's where none is named.
const kindOf = (name) => fields.follower_kinds.find((k) => k.name === (name || followerDefaults.kind)) ||
  {name, keys: [], roller: true, swinging: false};
const api = (path, params = {}) =>
  `/api/${path}?` + new URLSearchParams({session: SESSION, ...params}).toString();

// ---- cells -----------------------------------------------------------------------------

// A cell's text as a program value: a number where it reads as one, else the text itself (the
// library names what is wrong with it); empty: the key is left out.
function parseCell(text) {
  text = text.trim();
  if (text === "") return undefined;
  return NUMBER.test(text) ? Number(text) : text;
}

function parseEnd(text) {
  text = text.trim();
  if (text === "" || text === "match") return "match";
  const parts = text.split(",").map((s) => s.trim());
  if (parts.every((p) => NUMBER.test(p)) && parts.length <= 3) {
    const out = {};
    parts.forEach((p, i) => { out[END_KEYS[i]] = Number(p); });
    return out;
  }
  return text;
}

const showEnd = (v) => (v === undefined || v === "match") ? "match" :
  typeof v === "object" ? END_KEYS.filter((k) => k in v).map((k) => v[k]).join(", ") : String(v);

// ---- the editor ------------------------------------------------------------------------

function input(value, onChange, attrs = {}) {
  const el = document.createElement("input");
  el.value = value === undefined ? "" : value;
  el.size = attrs.size || 6;
  for (const [k, v] of Object.entries(attrs)) if (k !== "size") el.dataset[k] = v;
  el.addEventListener("input", () => { lastField = el; onChange(el.value); edited(); });
  return el;
}

function select(options, value, onChange, attrs = {}) {
  const el = document.createElement("select");
  const all = options.includes(value) ? options : [...options, value];
  for (const o of all) {
    const opt = document.createElement("option");
    opt.value = o; opt.textContent = o === "" ? "dwell" : lawLabel(o);
    el.appendChild(opt);
  }
  el.value = value;
  for (const [k, v] of Object.entries(attrs)) el.dataset[k] = v;
  el.addEventListener("change", () => { lastField = el; onChange(el.value); renderEditor(); edited(); });
  return el;
}

function cell(row, child) {
  const td = document.createElement("td");
  if (child) td.appendChild(typeof child === "string" ? document.createTextNode(child) : child);
  row.appendChild(td);
  return td;
}

// A segment's law changed: its lift kept (a dwell keeps it aside), a polynomial's ends set.
function setLaw(seg, law) {
  const wasPoly = seg.law === "polynomial";
  if (law === "") {
    if (seg.lift_mm !== undefined) dwellLift.set(seg, seg.lift_mm);
    for (const k of ["law", "lift_mm", "degree", "start", "end"]) delete seg[k];
    return;
  }
  seg.law = law;
  if (seg.lift_mm === undefined) seg.lift_mm = dwellLift.has(seg) ? dwellLift.get(seg) : 10;
  if (law === "polynomial" && !wasPoly) Object.assign(seg, {degree: 5, start: "match", end: "match"});
  if (law !== "polynomial") for (const k of ["degree", "start", "end"]) delete seg[k];
}

// The law cell: any law `camjax laws` names, parameters included (`triple-harmonic:A1,A2`,
// `modified-trapezoid-cv:P`), with the names as suggestions; empty is a dwell.
function lawInput(seg, n) {
  const el = document.createElement("input");
  el.value = seg.law || "";
  el.placeholder = "dwell";
  el.size = 16;
  el.setAttribute("list", "law-names");
  el.dataset.seg = n; el.dataset.key = "law";
  el.title = "a law of camjax laws (with its parameters, e.g. triple-harmonic:A1,A2), " +
    "constant-velocity, polynomial, a law file (.json); empty: a dwell";
  el.addEventListener("change", () => { lastField = null; setLaw(seg, el.value.trim()); renderEditor(); edited(); });
  return el;
}


// Beside each follower field, what it makes of the machine when empty (or does not do).
function renderFollowerNotes() {
  const f = model.follower || {}, flat = !kindOf(f.kind || followerDefaults.kind).roller;
  document.querySelectorAll("#follower .fnote").forEach((note) => {
    const key = note.dataset.note;
    note.textContent =
      key === "roller_radius_mm" && flat ? (rollerCleared ? "a flat face has no roller: cleared" : "a flat face has no roller") :
      f[key] === undefined ? emptyNote(key) :
      key === "preload_n" && f.spring_rate_n_per_mm === undefined ? "does nothing on a grooved cam (no spring)" : "";
  });
}

function renderLawNames() {
  let list = $("law-names");
  if (!list) { list = document.createElement("datalist"); list.id = "law-names"; document.body.appendChild(list); }
  list.innerHTML = "";
  for (const name of laws) { const o = document.createElement("option"); o.value = name; list.appendChild(o); }
}

// What an empty follower field makes of the machine: said beside it.
function emptyNote(key) {
  if (key === "spring_rate_n_per_mm") return "empty: no return spring, a grooved (form-closed) cam";
  const d = followerDefaults[key];
  return d === null || d === undefined ? "empty: none" : `empty: ${d} (the default)`;
}

function button(text, title, onClick) {
  const b = document.createElement("button");
  b.textContent = text; b.title = title;
  b.addEventListener("click", () => { lastField = null; onClick(); renderEditor(); edited(); });
  return b;
}

// A whole cam from one lift table ([program] file or points): no segments to edit.
const isTable = () => !!model && !model.segment && !!model.program &&
  (model.program.file !== undefined || model.program.points !== undefined);

// The table cam's segments (those its table was cut into), read-only, from the report.
function renderTableRows() {
  const body = $("segments").querySelector("tbody");
  body.innerHTML = "";
  for (const g of (report ? report.segments : [])) {
    const row = document.createElement("tr");
    row.dataset.seg = g.segment;
    row.className = "table-cam";
    for (const text of [String(g.segment), g.kind, fmt(g.lift_mm, 5), fmt(g.angle_deg, 5), "", "", "", ""]) cell(row, text);
    const notes = cell(row, g.kind !== "dwell" ? `peak y'' ${fmt(g.peak_acceleration_mm_per_deg2, 3)} mm/deg\u00b2` : "");
    notes.className = "notes";
    body.appendChild(row);
  }
}

function renderEditor() {
  $("name").value = (model.program || {}).name || "";
  const table = isTable();
  $("table-note").hidden = !table;
  $("add").hidden = table;
  $("design").hidden = table;
  const body = $("segments").querySelector("tbody");
  body.innerHTML = "";
  if (table) renderTableRows();
  (model.segment || []).forEach((seg, i) => {
    const n = i + 1, row = document.createElement("tr");
    row.dataset.seg = n;
    cell(row, String(n));
    cell(row, lawInput(seg, n));
    const set = (key) => (text) => { const v = parseCell(text); if (v === undefined) delete seg[key]; else seg[key] = v; };
    cell(row, seg.law ? input(seg.lift_mm, set("lift_mm"), {seg: n, key: "lift_mm"}) : null);
    cell(row, input(seg.angle_deg, set("angle_deg"), {seg: n, key: "angle_deg"}));
    const poly = seg.law === "polynomial";
    cell(row, poly ? select(["5", "7"], String(seg.degree || 5), (v) => { seg.degree = Number(v); },
      {seg: n, key: "degree"}) : null);
    for (const key of ["start", "end"])
      cell(row, poly ? input(showEnd(seg[key]), (t) => { seg[key] = parseEnd(t); }, {seg: n, key, size: 10}) : null);
    const tools = cell(row);
    tools.className = "tools";
    tools.append(
      button("\u2191", "move up", () => { if (i > 0) model.segment.splice(i - 1, 0, ...model.segment.splice(i, 1)); }),
      button("\u2193", "move down", () => { if (i < model.segment.length - 1) model.segment.splice(i + 1, 0, ...model.segment.splice(i, 1)); }),
      button("\u2715", "delete", () => { model.segment.splice(i, 1); }));
    cell(row).className = "notes";
    body.appendChild(row);
  });
  const box = $("follower");
  box.innerHTML = "";
  const f = model.follower = model.follower || {};
  const chained = Array.isArray(model.train);  // a chain gives these fields in its own tables
  for (const key of fields.follower) {
    // (one still set shows, so that the library's message naming it can be acted on)
    if (chained && fields.chain_replaces.includes(key) && f[key] === undefined) continue;
    const label = document.createElement("label");
    label.textContent = key + " ";
    if (key === "kind") {
      // a flat face has no roller: its radius goes with the switch (said beside the field)
      label.appendChild(select(fields.follower_kinds.map((k) => k.name), f.kind || followerDefaults.kind, (v) => {
        f.kind = v;
        if (!kindOf(v).roller && f.roller_radius_mm !== undefined) { delete f.roller_radius_mm; rollerCleared = true; }
      }, {key}));
    } else {
      label.appendChild(input(f[key], (t) => {
        const v = parseCell(t); if (v === undefined) delete f[key]; else f[key] = v;
        renderFollowerNotes();
      }, {key}));
      const note = document.createElement("span");
      note.className = "fnote";
      note.dataset.note = key;
      label.appendChild(note);
    }
    box.appendChild(label);
  }
  renderFollowerNotes();
  renderChain();
  renderArm();
  renderMaterials();
  rollerCleared = false;
  renderNotes();
  renderDesign();
}

// ---- talking to the server -------------------------------------------------------------

function setStatus(text, kind) {
  const s = $("status");
  s.textContent = text;
  s.className = kind || "";
}

// While an error stands the views show the last good program: they are marked stale, and
// "Save" says that it saves that program, not the one in the tables.
function markStale(stale) {
  document.body.dataset.stale = stale ? "1" : "0";
  $("views").title = stale ? "the last good program: the tables hold an error" : "";
  const save = $("save");
  save.textContent = (bundle ? "Save TOML + laws (zip)" : "Save TOML") + (stale ? " (last good program)" : "");
  save.title = stale ? "saves the last good program, not the tables' (they hold an error)" : "";
}

function clearErrors() {
  document.querySelectorAll(".err").forEach((e) => e.remove());
  document.querySelectorAll(".bad").forEach((e) => e.classList.remove("bad"));
  markStale(false);
  errorFrom = null;
}

function showError(message, from = "program") {
  clearErrors();
  errorFrom = from;
  markStale(from === "program");
  setStatus(message, "error");
  const span = document.createElement("span");
  span.className = "err";
  span.textContent = message;
  const m = /^segment (\d+)/.exec(message), b = /^\[\[train\]\] body (\d+)/.exec(message);
  const row = m ? document.querySelector(`#segments tr[data-seg="${m[1]}"]`) :
    b ? document.querySelector(`#train tr[data-body="${b[1]}"]`) : null;
  if (row) row.classList.add("bad");
  const field = lastField && document.body.contains(lastField) ? lastField : null;
  // the field the message names, else the one edited last unless the message names a row
  // it is not in (a segment's or a body's)
  const named = namedField(message);
  if (named) named.insertAdjacentElement("afterend", span);
  else if (field && (!row || row.contains(field))) field.insertAdjacentElement("afterend", span);
  else if (row) row.querySelector(".notes").appendChild(span);
  else if (/^\[arm\]/.test(message) && !$("arm-box").hidden) $("arm-notes").appendChild(span);
  else $("headline").insertAdjacentElement("beforebegin", span);
}

// The input of the field a message names first (`[arm] needs bending_stiffness_n_m2`,
// `[follower] mass_kg, ...: ...`) where the page shows it; else null.
function namedField(message) {
  const m = /^\[(follower|arm|spring|seat|materials)\]:? (?:needs )?(\w+)/.exec(message);
  return m ? document.querySelector(`#${m[1]} [data-key="${m[2]}"]`) : null;
}

function edited() {
  rememberEdit();
  dirty = true;
  clearTimeout(timer);
  timer = setTimeout(send, 400);
}

async function send() {
  if (inFlight) return;            // the answer will send the latest edit
  dirty = false;
  inFlight = true;
  document.body.dataset.busy = "1";
  setStatus("computing\u2026", "busy");
  try {
    const response = await fetch(api("program", {rpm: rpmText, ...(opened ? {opened: 1} : {})}),
      {method: "POST", body: JSON.stringify(model), headers: {"Content-Type": "application/json"}});
    const answer = await response.json();
    if (!response.ok) { showError(answer.error); return; }
    report = answer;
    clearErrors();
    if (chosen !== null && chosen < Math.min(...report.speeds.map((x) => x.rpm))) chosen = null;
    await loadCurves();
  } catch (error) {
    showError(`no answer from the studio (${error})`);
  } finally {
    inFlight = false;
    if (dirty) send(); else document.body.dataset.busy = "0";
  }
}

async function loadCurves() {
  const params = chosen === null ? {} : {rpm: chosen};
  const response = await fetch(api("curves", params));
  const answer = await response.json();
  if (!response.ok) { showError(answer.error, "chosen"); return; }
  if (errorFrom === "chosen") clearErrors();  // a good speed clears the bad one's message
  curves = answer;
  chosen = curves.rpm;
  $("chosen").value = chosen;
  setStatus("ready", "ok");
  draw();
}

async function start() {
  const response = await fetch(api("program"));
  const state = await response.json();
  if (!response.ok) { showError(state.error); return; }
  load(state);
  send();
}

function load(state) {
  model = state.program;
  laws = state.laws || laws;
  rpmText = state.rpm;
  bundle = !!state.bundle;
  designDefaults = state.design || designDefaults;
  followerDefaults = state.follower_defaults || followerDefaults;
  fields = state.fields || fields;
  materialDefaults = state.materials_defaults || materialDefaults;
  renderLawNames();
  $("range").value = rpmText;
  $("save").href = api(bundle ? "program.zip" : "program.toml");
  markStale(false);
  renderEditor();
  forgetEdits();
}

// ---- designing a segment's law ---------------------------------------------------------

// The moving segments to choose from; the band defaults to the speed range.
function renderDesign() {
  const pick = $("d-seg"), was = pick.value;
  pick.innerHTML = "";
  (model.segment || []).forEach((seg, i) => {
    if (!seg.law) return;
    const opt = document.createElement("option");
    opt.value = i + 1; opt.textContent = `${i + 1} (${lawLabel(seg.law)})`;
    pick.appendChild(opt);
  });
  if ([...pick.options].some((o) => o.value === was)) pick.value = was;
  // the objectives this program takes: the server's rule (its report), in the server's words
  const objective = $("d-obj"), wasObjective = objective.value;
  objective.innerHTML = "";
  ((report && report.design_objectives) || designDefaults.objectives || []).forEach((o) => {
    const opt = document.createElement("option");
    opt.value = o.name; opt.textContent = o.label;
    objective.appendChild(opt);
  });
  if ([...objective.options].some((o) => o.value === wasObjective)) objective.value = wasObjective;
  $("d-start").disabled = !objective.options.length || $("design").dataset.state === "running";
  $("d-start").title = objective.options.length ? "" : "no design objective applies to this program";
  if (!$("d-steps").value) $("d-steps").value = designDefaults.steps;
  if (report && !$("d-lo").value) {
    const rpm = report.speeds.map((x) => x.rpm);
    $("d-lo").value = Math.min(...rpm); $("d-hi").value = Math.max(...rpm);
  }
}

// A law file's name, not its folder (a designed law's file lives in the studio's folder).
const lawLabel = (law) => law.endsWith(".json") ? law.split("/").pop() : law;

function designState(state) {
  $("design").dataset.state = state;
}

async function startDesign() {
  $("d-message").textContent = "";
  const params = {segment: $("d-seg").value, objective: $("d-obj").value,
    rpm: `${$("d-lo").value.trim()}:${$("d-hi").value.trim()}`, steps: $("d-steps").value.trim()};
  const response = await fetch(api("design", params), {method: "POST"});
  const answer = await response.json();
  if (!response.ok) { $("d-message").textContent = answer.error; return; }
  $("d-result").hidden = true;
  showProgress(answer);
  clearInterval(polling);
  polling = setInterval(pollDesign, 500);
}

function showProgress(job) {
  designState(job.state);
  $("d-progress").hidden = false;
  $("d-start").disabled = job.state === "running";
  $("d-bar").max = job.steps; $("d-bar").value = job.step;
  $("d-phase").textContent = job.state === "running" ?
    `${job.phase}: step ${job.step} of ${job.steps}, ${job.seconds.toFixed(0)} s` :
    `${job.state}: ${job.steps} steps in ${job.seconds.toFixed(1)} s`;
}

async function pollDesign() {
  const job = await (await fetch(api("design"))).json();
  showProgress(job);
  if (job.state === "running") return;
  clearInterval(polling);
  if (job.state === "error") { $("d-message").textContent = job.message; return; }
  if (job.state === "done") showDesign(job);
}

// Before and after: the objective's values and the speed curves over the range.
function showDesign(job) {
  const change = 100 * (job.after - job.before) / Math.abs(job.before);
  $("d-values").innerHTML =
    `<div>${job.label}: <b id="d-before" data-value="${job.before}">${fmt(job.before, 5)}</b> with the segment's own law, ` +
    `<b id="d-after" data-value="${job.after}">${fmt(job.after, 5)}</b> designed (${change.toFixed(1)} %)</div>` +
    (job.kept_initial ? "<div>the design did not improve on the segment's own law: keeping it changes nothing</div>" : "");
  $("d-result").hidden = false;
  const b = job.curves.before, a = job.curves.after;
  const marks = [{x: job.rpm[0], label: "band", color: "#777"}, {x: job.rpm[1], color: "#777"}];
  const so = {xlabel: "speed (rpm)", points: true, marks};
  plot("c-d-preload", "minimum preload (N): before and after", b.rpm, [
    {label: "before", y: b.min_preload_n, dash: [4, 3], color: "#777"}, {label: "after", y: a.min_preload_n}], so);
  plot("c-d-residual", "largest residual vibration (mm): before and after", b.rpm, [
    {label: "before", y: b.max_residual_mm, dash: [4, 3], color: "#777"}, {label: "after", y: a.max_residual_mm}], so);
  const seated = b.seating_velocity_m_s !== null && b.seating_velocity_m_s !== undefined;
  $("c-d-seating").hidden = !seated;
  if (seated) plot("c-d-seating", "valve seating velocity (m/s): before and after", b.rpm, [
    {label: "before", y: b.seating_velocity_m_s, dash: [4, 3], color: "#777"},
    {label: "after", y: a.seating_velocity_m_s}], so);
}

async function finishDesign(action) {
  $("d-message").textContent = "";
  document.body.dataset.busy = "1";
  try {
    const response = await fetch(api(`design/${action}`), {method: "POST"});
    const answer = await response.json();
    if (!response.ok) { $("d-message").textContent = answer.error; return; }
    $("d-result").hidden = true;
    $("d-progress").hidden = true;
    designState(action === "keep" ? "kept" : "discarded");
    if (action === "keep") {
      report = answer;
      load(await (await fetch(api("program"))).json());
      clearErrors();
      await loadCurves();
    }
  } finally {
    document.body.dataset.busy = "0";
  }
}

// ---- drawing ---------------------------------------------------------------------------

const fmt = (v, d = 4) => v === null || v === undefined ? "-" : Number(v).toPrecision(d);

function plot(id, title, x, series, opts = {}) {
  const el = $(id);
  if (charts[id]) { charts[id].destroy(); delete charts[id]; }
  el.innerHTML = "";
  if (!series.length) return;
  // a series the report leaves empty (not computed for this program) is not drawn; none: said
  const given = series.filter((s) => (s.y || []).some((v) => v !== null && v !== undefined));
  if (!given.length) { el.textContent = `${title}: not in the report for this program`; return; }
  series = given;
  const colors = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf"];
  const width = Math.max(300, el.clientWidth - 8);
  charts[id] = new uPlot({
    title, width, height: opts.height || 200,
    legend: {live: false},
    scales: {x: {time: false}},
    axes: [{label: opts.xlabel || "cam angle (deg)",
      ...(opts.xticks ? {splits: () => opts.xticks.map((_, i) => i + 1), values: () => opts.xticks} : {})},
    {label: opts.ylabel || "", size: 60}],
    series: [{}, ...series.map((s, i) => ({label: s.label, stroke: s.color || colors[i % colors.length],
      width: 1.2, dash: s.dash, ...(opts.lines === false ? {paths: () => null} : {}),
      points: {show: !!opts.points, size: opts.lines === false ? 6 : 5, fill: s.color || colors[i % colors.length]}}))],
    hooks: {draw: [(u) => (opts.marks || []).forEach((m) => mark(u, m))]},
  }, [x, ...series.map((s) => s.y)], el);
}

// A vertical line at x = m.x (the jump speed) or a horizontal one at y = m.y.
function mark(u, m) {
  const ctx = u.ctx;
  ctx.save();
  ctx.strokeStyle = m.color || "#d62728";
  ctx.setLineDash([5, 4]);
  ctx.lineWidth = 1.5;
  ctx.beginPath();
  if (m.x !== undefined) {
    const x = u.valToPos(m.x, "x", true);
    ctx.moveTo(x, u.bbox.top); ctx.lineTo(x, u.bbox.top + u.bbox.height);
    ctx.fillStyle = ctx.strokeStyle;
    ctx.fillText(m.label || "", x + 4, u.bbox.top + 12);
  } else {
    const y = u.valToPos(m.y, "y", true);
    ctx.moveTo(u.bbox.left, y); ctx.lineTo(u.bbox.left + u.bbox.width, y);
  }
  ctx.stroke();
  ctx.restore();
}

function draw() {
  if (!report || !curves) return;
  const k = curves.kinematics, r = curves.response, f = curves.follower;
  plot("c-lift", "lift y (mm)", k.theta_deg, [{label: "y", y: k.lift_mm}]);
  plot("c-vel", "velocity y' (mm/deg)", k.theta_deg, [{label: "y'", y: k.velocity_mm_per_deg}]);
  plot("c-acc", "acceleration y'' (mm/deg\u00b2)", k.theta_deg, [{label: "y''", y: k.acceleration_mm_per_deg2}]);
  plot("c-jerk", "jerk y''' (mm/deg\u00b3)", k.theta_deg, [{label: "y'''", y: k.jerk_mm_per_deg3}]);
  const at = `at ${fmt(curves.rpm, 5)} rpm`;
  // a chain's payload is its last body; its rigid force is not served (the one-body limit)
  plot("c-payload", `acceleration ${at} (m/s\u00b2)`, r.theta_deg, [
    {label: "payload x''", y: r.payload_acceleration_m_s2},
    {label: "rigid follower y''", y: r.kinematic_acceleration_m_s2, dash: [4, 3]}]);
  plot("c-force", `contact force ${at} (N)`, r.theta_deg, [
    {label: "elastic train", y: r.contact_force_n},
    {label: "rigid follower", y: r.rigid_contact_force_n, dash: [4, 3]}],
  {marks: [{y: 0, color: "#000"}, ...(f.form_closed ? [] : [{y: f.preload_n, color: "#ff7f0e"}])]});
  const speeds = report.speeds, rpm = speeds.map((s) => s.rpm);
  const jumpMark = report.jump_speed_rpm === null ? [] :
    [{x: report.jump_speed_rpm, label: `jump ${report.jump_speed_rpm.toFixed(1)} rpm`}];
  const so = {xlabel: "speed (rpm)", points: true, marks: jumpMark};
  plot("c-preload", "minimum preload (N) vs speed", rpm,
    f.form_closed ? [] : [{label: "min preload", y: speeds.map((s) => s.min_preload_n)}],
    {...so, marks: [...jumpMark, {y: f.preload_n, color: "#ff7f0e"}]});
  const still = report.residual_segments || [];  // the program's rule, from the server
  plot("c-residual", "residual vibration (mm) vs speed", rpm,
    still.map((n, i) => ({label: `segment ${n}`, y: speeds.map((s) => (s.residual_vibration_mm || [])[i])}))
      .filter((series) => series.y.some((v) => v !== null && v !== undefined)), so);
  plot("c-torque-speed", "drive torque (N m) vs speed", rpm, [
    {label: "peak |T|", y: speeds.map((s) => s.max_drive_torque_n_m)},
    {label: "RMS T", y: speeds.map((s) => s.rms_drive_torque_n_m)}], so);
  plot("c-torque-turn", `drive torque ${at} (N m)`, r.theta_deg, [{label: "T", y: r.drive_torque_n_m}],
    {marks: [{y: 0, color: "#000"}]});
  const stressed = speeds.some((s) => s.max_contact_stress_mpa !== null && s.max_contact_stress_mpa !== undefined);
  plot("c-stress-turn", stressed ? `Hertz stress ${at} (MPa)` : "Hertz stress: set follower contact_width_mm",
    r.theta_deg, stressed ? [{label: "p", y: r.contact_stress_mpa}] : []);
  plot("c-stress-speed", "peak Hertz stress (MPa) vs speed", rpm,
    stressed ? [{label: "max p", y: speeds.map((s) => s.max_contact_stress_mpa)}] : [], so);
  if (!stressed) for (const id of ["c-stress-turn", "c-stress-speed"])
    $(id).textContent = "Hertz stress: give the follower's contact_width_mm";
  drawHeadline();
  drawJoins();
  renderNotes();
  if (!isTable()) renderDesign();
  drawProfile();
  drawMotor();
  drawTrain();
}

function drawHeadline() {
  const s = report.speeds.reduce((best, x) => Math.abs(x.rpm - curves.rpm) < Math.abs(best.rpm - curves.rpm) ? x : best);
  const jump = report.jump_below_range ? "below the range" :
    report.jump_speed_rpm === null ? "none in the range" : `${report.jump_speed_rpm.toFixed(1)} rpm`;
  const g = report.geometry || {};
  $("headline").innerHTML =
    `<div>jump speed <b id="jump" data-rpm="${report.jump_speed_rpm}">${jump}</b></div>` +
    `<div>at ${fmt(s.rpm, 5)} rpm (range speed nearest the chosen): min preload ${fmt(s.min_preload_n)} N, ` +
    `contact force ${fmt(s.min_contact_force_n)} to ${fmt(s.max_contact_force_n)} N, ` +
    `peak torque ${fmt(s.max_drive_torque_n_m)} N m, RMS ${fmt(s.rms_drive_torque_n_m)} N m</div>` +
    `<div>max pressure angle ${fmt(g.max_pressure_angle_deg)} deg, min radius of curvature ` +
    `${fmt(g.min_radius_of_curvature_mm)} mm</div>`;
}

function drawJoins() {
  const body = $("joins").querySelector("tbody");
  body.innerHTML = report.joins.map((j) =>
    `<tr><td>${j.before}|${j.after}</td><td>${fmt(j.angle_deg, 5)}</td><td>${j.state}</td><td>${j.continuity}</td>` +
    `<td>${fmt(j.velocity_mm_per_deg)}</td><td>${fmt(j.acceleration_before_mm_per_deg2)}</td>` +
    `<td>${fmt(j.acceleration_after_mm_per_deg2)}</td></tr>`).join("");
  const list = $("warnings");
  list.innerHTML = "";
  for (const w of (curves.warnings || [])) {
    const li = document.createElement("li"); li.textContent = w; list.appendChild(li);
  }
}

// Each segment's notes: its kind and peaks, an overshoot, an acceleration step at its start,
// where contact is lost in it at the range speed nearest the chosen one.
function renderNotes() {
  if (!report || !model) return;
  if (isTable()) { renderTableRows(); return; }
  const speed = report.speeds.reduce((best, x) => curves && Math.abs(x.rpm - curves.rpm) < Math.abs(best.rpm - curves.rpm) ? x : best);
  let angle = 0;
  const starts = model.segment.map((s) => { const a = angle; angle += Number(s.angle_deg) || 0; return a; });
  document.querySelectorAll("#segments tbody tr").forEach((row, i) => {
    const notes = row.querySelector(".notes");
    if (notes.querySelector(".err")) return;
    const g = report.segments[i];
    const out = [];
    if (g && g.segment === i + 1 && report.segments.length === model.segment.length) {
      if (g.kind !== "dwell" && g.kind !== "constant-velocity") out.push(`peak y'' ${fmt(g.peak_acceleration_mm_per_deg2, 3)} mm/deg\u00b2`);
      if (g.overshoot) out.push("\u26a0 overshoots its ends");
      const join = report.joins.find((j) => j.after === i + 1);
      if (join && join.continuity !== "C2") out.push(`\u26a0 acceleration steps at its start (${join.continuity})`);
      for (const fl of speed.flights || []) {
        const a = fl.separation_deg;
        if (a >= starts[i] && a < starts[i] + (Number(model.segment[i].angle_deg) || 0))
          out.push(`\u26a0 loses contact at ${fmt(a, 4)} deg`);
      }
    }
    notes.textContent = out.join("; ");
  });
}

function drawProfile() {
  const canvas = $("profile"), ctx = canvas.getContext("2d");
  const p = curves.profile, f = curves.follower, kind = kindOf(f.kind);
  const deg = Number($("angle").value);
  $("angle-text").textContent = `${deg} deg`;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  const pts = [...p.pitch, ...p.profile, ...(p.outer || [])];
  const reach = Math.max(Math.max(...pts.map(([x, y]) => Math.hypot(x, y))) + (f.roller_radius_mm || 0) * 2 + 5,
    kind.swinging ? f.pivot_mm + 8 : 0);
  const scale = canvas.width / 2 / reach, cx = canvas.width / 2, cy = canvas.height / 2;
  const t = deg * Math.PI / 180, c = Math.cos(t), s = Math.sin(t);
  // the cam turns by the cam angle; the follower stays on its axis (camjax.geometry's frame)
  const at = ([x, y]) => [cx + scale * (c * x - s * y), cy - scale * (s * x + c * y)];
  const path = (points, style, dash) => {
    ctx.beginPath(); ctx.strokeStyle = style; ctx.setLineDash(dash || []);
    points.forEach((q, i) => { const [u, v] = at(q); if (i) ctx.lineTo(u, v); else ctx.moveTo(u, v); });
    ctx.closePath(); ctx.stroke();
  };
  path(p.profile, "#1f77b4");
  if (p.outer) path(p.outer, "#1f77b4");
  if (!p.flat_face) path(p.pitch, "#999", [4, 4]);
  ctx.setLineDash([]);
  const i = Math.round(deg / 360 * p.theta_deg.length) % p.theta_deg.length;
  ctx.strokeStyle = "#d62728"; ctx.lineWidth = 2;
  if (p.flat_face && kind.swinging) {
    drawSwingingArm(ctx, at(p.profile[i]), cx + scale * f.pivot_mm, cy, true);
  } else if (p.flat_face) {
    const [u, v] = at(p.profile[i]);
    ctx.beginPath(); ctx.moveTo(u - 60, v); ctx.lineTo(u + 60, v); ctx.stroke();
  } else {
    const [u, v] = at(p.pitch[i]);
    ctx.beginPath(); ctx.arc(u, v, scale * f.roller_radius_mm, 0, 2 * Math.PI); ctx.stroke();
    if (!kind.swinging) { ctx.beginPath(); ctx.moveTo(u, v); ctx.lineTo(u, 0); ctx.stroke(); }
    else drawSwingingArm(ctx, [u, v], cx + scale * f.pivot_mm, cy, false);
  }
  drawRotation(ctx, cx, cy, Math.min(40, scale * f.base_radius_mm * 0.5));
  ctx.lineWidth = 1;
  ctx.beginPath(); ctx.arc(cx, cy, 3, 0, 2 * Math.PI); ctx.fillStyle = "#000"; ctx.fill();
}

// ---- the servo motor ------------------------------------------------------------------
// A program with a [drive] and motors: the report's "motor" (camjax.program.program_motor_choice)
// drawn as a table per speed, its checks, and the (speed, torque) points over the envelope.

function drawMotor() {
  const box = $("motor-box"), sizing = report.motor;
  box.hidden = !sizing;
  if (!sizing) return;
  const verdict = sizing.picked ? `picked motor <b>${sizing.picked}</b>, the smallest that passes at every speed` :
    `no motor passes; the closest is <b>${sizing.closest}</b>`;
  $("motor-verdict").innerHTML = verdict;
  $("motor-verdict").dataset.motor = sizing.shown;
  const pct = (v) => `${(100 * v).toFixed(1)}%`;
  $("motor-speeds").querySelector("tbody").innerHTML = sizing.sizings.map((s) => {
    const d = s.dynamic, g = s.rigid;
    return `<tr class="${s.passed ? "" : "bad"}"><td>${fmt(s.rpm, 5)}</td>` +
      `<td>${fmt(d.peak_torque_n_m)} (${fmt(g.peak_torque_n_m)})</td><td>${fmt(d.rms_torque_n_m)} (${fmt(g.rms_torque_n_m)})</td>` +
      `<td>${fmt(d.max_speed_rpm, 5)}</td><td>${fmt(s.inertia_ratio, 3)}</td><td>${pct(d.thermal_use)}</td>` +
      `<td>${s.passed ? "passes" : "fails"}</td></tr>`;
  }).join("");
  const names = sizing.sizings[0].dynamic.checks.map((c) => c.name);
  $("motor-checks").querySelector("thead").innerHTML =
    `<tr><th>check (dynamic)</th>${sizing.sizings.map((s) => `<th>${fmt(s.rpm, 5)} rpm</th>`).join("")}</tr>`;
  $("motor-checks").querySelector("tbody").innerHTML = names.map((name, i) => `<tr><td>${name}</td>` +
    sizing.sizings.map((s) => {
      const c = s.dynamic.checks[i];
      return `<td class="${c.passed ? "" : "bad"}" title="${fmt(c.value)} against ${fmt(c.limit)}">` +
        `${c.passed ? "pass" : "FAIL"} ${c.margin >= 0 ? "+" : ""}${pct(c.margin)}</td>`;
    }).join("") + "</tr>").join("");
  drawTorqueSpeed(sizing);
}

// The (speed, torque) points of every speed over one turn (dynamic: dots, rigid: a thin line)
// inside the envelope mirrored to the four quadrants, as camjax.program.motor_figure draws them.
function drawTorqueSpeed(sizing) {
  const canvas = $("motor-plot"), ctx = canvas.getContext("2d");
  canvas.width = Math.max(300, $("motor-box").clientWidth - 16);
  const w = canvas.width, h = canvas.height, pad = 44;
  const env = sizing.envelope;
  const points = sizing.sizings.flatMap((s) => [...s.dynamic.points, ...s.rigid.points]);
  const xmax = 1.05 * Math.max(...env.map((p) => p[0]), ...points.map((p) => Math.abs(p[0])));
  const ymax = 1.1 * Math.max(...env.map((p) => p[1]), ...points.map((p) => Math.abs(p[1])));
  const X = (v) => pad + (v + xmax) / (2 * xmax) * (w - 2 * pad), Y = (v) => h / 2 - v / ymax * (h / 2 - 20);
  ctx.clearRect(0, 0, w, h);
  ctx.font = "12px system-ui"; ctx.fillStyle = "#222"; ctx.textAlign = "center";
  ctx.fillText(`motor ${sizing.shown}: torque (N m) against speed (rpm) over one turn`, w / 2, 13);
  ctx.strokeStyle = "#ccc"; ctx.beginPath();
  ctx.moveTo(X(-xmax), Y(0)); ctx.lineTo(X(xmax), Y(0)); ctx.moveTo(X(0), Y(-ymax)); ctx.lineTo(X(0), Y(ymax)); ctx.stroke();
  ctx.fillText(`\u00b1${fmt(xmax, 3)} rpm`, X(xmax) - 30, Y(0) - 4);
  ctx.textAlign = "left"; ctx.fillText(`${fmt(ymax, 3)} N m`, X(0) + 4, Y(ymax) + 10);
  ctx.strokeStyle = "#000"; ctx.lineWidth = 1.5;
  for (const [sx, sy] of [[1, 1], [-1, 1], [1, -1], [-1, -1]]) {
    ctx.beginPath();
    env.forEach(([n, t], i) => (i ? ctx.lineTo : ctx.moveTo).call(ctx, X(sx * n), Y(sy * t)));
    ctx.lineTo(X(sx * env[env.length - 1][0]), Y(0));  // no torque past the last speed
    ctx.stroke();
  }
  ctx.lineWidth = 1;
  const colors = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"];
  sizing.sizings.forEach((s, k) => {
    const color = colors[k % colors.length];
    ctx.strokeStyle = color; ctx.globalAlpha = 0.6; ctx.beginPath();
    s.rigid.points.forEach(([n, t], i) => (i ? ctx.lineTo : ctx.moveTo).call(ctx, X(n), Y(t)));
    ctx.stroke(); ctx.globalAlpha = 1; ctx.fillStyle = color;
    for (const [n, t] of s.dynamic.points) ctx.fillRect(X(n) - 1, Y(t) - 1, 2, 2);
    ctx.fillRect(X(0) - 3, Y(s.dynamic.rms_torque_n_m) - 3, 6, 6);  // its RMS torque, as motor.png marks it
    ctx.fillText(`${fmt(s.rpm, 5)} rpm: dots dynamic, line rigid, square RMS`, pad, h - 8 - 14 * (sizing.sizings.length - 1 - k));
  });
  // the RMS limit: rms_share_limit (80%) of the continuous stall torque, as motor.png draws it
  const share = sizing.sizings[0].rms_share_limit, limit = share * sizing.continuous_stall_torque_n_m;
  if (Number.isFinite(limit)) {
    ctx.save(); ctx.strokeStyle = "#000"; ctx.setLineDash([2, 3]); ctx.beginPath();
    for (const sy of [1, -1]) { ctx.moveTo(X(-xmax), Y(sy * limit)); ctx.lineTo(X(xmax), Y(sy * limit)); }
    ctx.stroke(); ctx.restore();
    ctx.fillStyle = "#000"; ctx.textAlign = "right";
    ctx.fillText(`${fmt(100 * share, 3)}% of continuous stall torque (${fmt(limit, 3)} N m): the RMS limit`,
      X(xmax) - 4, Y(limit) - 4);
    ctx.textAlign = "left";
  }
  canvas.dataset.rmsLimit = limit;
}

// ---- materials: [materials], the elastic constants of the Hertz stress --------------------

let materialDefaults = {};          // each field of [materials] and what it stands for empty (GET /api/program)

// Like the follower's fields: an empty one is left out of [materials] (its default said
// beside it); no field set, no [materials] table.
function renderMaterials() {
  const box = $("materials");
  box.innerHTML = "";
  for (const key of Object.keys(materialDefaults)) {
    const label = document.createElement("label");
    label.textContent = key + " ";
    const note = document.createElement("span");
    note.className = "fnote";
    note.dataset.note = key;
    const say = () => {
      const d = materialDefaults[key];
      note.textContent = (model.materials || {})[key] === undefined && d !== undefined ? `empty: ${d} (the default)` : "";
    };
    label.appendChild(input((model.materials || {})[key], (t) => {
      const v = parseCell(t), m = model.materials = model.materials || {};
      if (v === undefined) delete m[key]; else m[key] = v;
      if (!Object.keys(m).length) delete model.materials;
      say();
    }, {key}));
    label.appendChild(note);
    say();
    box.appendChild(label);
  }
}

// ---- the profile view's follower arm and turning direction -------------------------------

// A swinging follower's arm from its pivot (fixed at pivot_mm on the x axis, camjax.geometry's
// frame) to the roller centre, or its face: the line through the pivot and the contact point.
function drawSwingingArm(ctx, [u, v], px, py, face) {
  ctx.beginPath(); ctx.moveTo(px, py);
  if (face) {
    const d = Math.hypot(u - px, v - py) || 1;
    ctx.lineTo(u + 40 * (u - px) / d, v + 40 * (v - py) / d);
  } else ctx.lineTo(u, v);
  ctx.stroke();
  ctx.lineWidth = 1;
  ctx.beginPath(); ctx.arc(px, py, 5, 0, 2 * Math.PI); ctx.fillStyle = "#fff"; ctx.fill(); ctx.stroke();
  ctx.beginPath(); ctx.moveTo(px - 8, py + 9); ctx.lineTo(px + 8, py + 9); ctx.stroke();  // the frame it hangs on
  ctx.lineWidth = 2;
}

// The cam turns counter-clockwise (camjax's convention; the library has no other): an arrow
// round the centre says so.
function drawRotation(ctx, cx, cy, r) {
  const end = -1.4;
  ctx.save();
  ctx.strokeStyle = "#555"; ctx.fillStyle = "#555"; ctx.lineWidth = 1; ctx.setLineDash([]);
  ctx.beginPath(); ctx.arc(cx, cy, r, 0.2, end, true); ctx.stroke();
  const x = cx + r * Math.cos(end), y = cy + r * Math.sin(end);
  const tx = Math.sin(end), ty = -Math.cos(end);  // the direction of travel on the screen
  ctx.beginPath(); ctx.moveTo(x + 7 * tx, y + 7 * ty);
  ctx.lineTo(x - 3 * ty, y + 3 * tx); ctx.lineTo(x + 3 * ty, y - 3 * tx); ctx.closePath(); ctx.fill();
  ctx.font = "11px system-ui, sans-serif";
  ctx.fillText("counter-clockwise", cx + r * 0.75, cy - r * 0.75 - 4);
  ctx.restore();
}

// ---- the chain of bodies: [[train]], [spring], [seat] ------------------------------------
// Its fields come from the server (GET /api/program's `fields`: the chain's own types); an
// empty field is left out of the program, which then takes the library's default or names
// what is missing in its one-line error, shown at the field.

function renderChain() {
  const box = $("chain-box"), bodies = model.train;
  box.hidden = !Array.isArray(bodies);
  if (box.hidden) return;
  const columns = fields.body.map((x) => x.name);
  const empty = Object.fromEntries(fields.body.map((x) => [x.name, x.required ? "required" : x.default === null ? "" : String(x.default)]));
  $("train").querySelector("thead").innerHTML =
    `<tr><th>#</th>${columns.map((c) => `<th>${c}</th>`).join("")}<th></th><th>notes</th></tr>`;
  const body = $("train").querySelector("tbody");
  body.innerHTML = "";
  bodies.forEach((b, i) => {
    const n = i + 1, row = document.createElement("tr");
    row.dataset.body = n;
    cell(row, String(n));
    for (const key of columns) {
      const text = key === "name" ? (t) => { if (t.trim() === "") delete b.name; else b.name = t; } :
        (t) => { const v = parseCell(t); if (v === undefined) delete b[key]; else b[key] = v; };
      const el = cell(row, input(b[key], text, {body: n, key, size: key === "name" ? 8 : 6})).firstChild;
      el.placeholder = key === "name" ? `body ${n}` : empty[key];  // what an empty field stands for
    }
    const tools = cell(row);
    tools.className = "tools";
    tools.append(
      button("\u2191", "move up (toward the cam)", () => { if (i > 0) bodies.splice(i - 1, 0, ...bodies.splice(i, 1)); }),
      button("\u2193", "move down", () => { if (i < bodies.length - 1) bodies.splice(i + 1, 0, ...bodies.splice(i, 1)); }),
      button("\u2715", "delete the body", () => { bodies.splice(i, 1); }));
    cell(row).className = "notes";
    body.appendChild(row);
  });
  for (const table of ["spring", "seat"]) renderRecord(table, fields[table]);
}

// The fields of one table ([spring], [seat] or [arm]); every field empty: no such table,
// unless `keep` (the [arm], which its own button adds and removes).
function renderRecord(table, spec, keep = false) {
  const box = $(table);
  box.innerHTML = "";
  for (const {name, required, default: d, empty} of spec) {
    const label = document.createElement("label");
    label.textContent = name + " ";
    label.appendChild(input((model[table] || {})[name], (t) => {
      const v = parseCell(t), rec = model[table] = model[table] || {};
      if (v === undefined) delete rec[name]; else rec[name] = v;
      if (!keep && !Object.keys(rec).length) delete model[table];
    }, {table, key: name}));
    const note = document.createElement("span");
    note.className = "fnote";
    note.textContent = (model[table] || {})[name] !== undefined ? "" :
      !required ? `empty: ${empty !== undefined ? empty : d === null ? "the library's choice" : d}` :
      model[table] ? "empty: required" : `empty: no [${table}]`;
    label.appendChild(note);
    box.appendChild(label);
  }
}

// The report's train section (camjax.program's train_section), read key by key so what
// the library adds shows: the natural frequencies and mode shapes (one small plot per mode
// over the bodies), the harmonic check, and a row per speed of every per-speed value.
function drawTrain() {
  const t = report.train, box = $("train-box");
  box.hidden = !t;
  if (!t) return;
  $("train-note").textContent = t.note || "";
  const shown = new Set(["note", "bodies", "speeds", "harmonic_check", "one_body", "arm"]);
  const facts = Object.entries(t).filter(([k, v]) => !shown.has(k) && !k.startsWith("mode_shapes_") &&
    !k.startsWith("natural_frequencies_"));
  const freq = (key) => (t[key] || []).map((f) => fmt(f, 5)).join(", ");
  $("train-facts").innerHTML =
    `<div>natural frequencies, cam contact held: <b id="train-held" data-hz="${JSON.stringify(t.natural_frequencies_held_hz || [])}">` +
    `${freq("natural_frequencies_held_hz")}</b> Hz</div>` +
    `<div>free (in flight): <b id="train-free" data-hz="${JSON.stringify(t.natural_frequencies_free_hz || [])}">` +
    `${freq("natural_frequencies_free_hz")}</b> Hz</div>` +
    facts.map(([k, v]) => `<div>${k}: ${typeof v === "number" ? fmt(v, 6) : v === null ? "none" : JSON.stringify(v)}</div>`).join("");
  drawModes(t);
  drawHarmonics(t);
  drawTrainSpeeds(t);
  drawArm(t.arm);
}

function drawModes(t) {
  const box = $("train-modes"), held = t.mode_shapes_held || [], free = t.mode_shapes_free || [];
  for (const id of Object.keys(charts).filter((k) => k.startsWith("c-mode-"))) { charts[id].destroy(); delete charts[id]; }
  box.innerHTML = "";
  const x = t.bodies.map((_, i) => i + 1);
  // mode k held and free (the free chain has one more: the cam's contact let go)
  [...Array(Math.max(held.length, free.length)).keys()].forEach((k) => {
    const el = document.createElement("div");
    el.className = "chart"; el.id = `c-mode-${k + 1}`;
    box.appendChild(el);
    const series = [];
    if (held[k]) series.push({label: `held ${fmt(t.natural_frequencies_held_hz[k], 5)} Hz`, y: held[k]});
    if (free[k]) series.push({label: `free ${fmt(t.natural_frequencies_free_hz[k], 5)} Hz`, y: free[k], dash: [4, 3],
      color: "#ff7f0e"});
    plot(el.id, `mode ${k + 1}`, x, series,
      {xlabel: `body (${t.bodies.join(", ")})`, points: true, height: 140, xticks: t.bodies});
  });
}

// Each mode's frequency f against the cam orders n that meet it in the speed range: the
// speed 60 f / n at which order n excites it (the harmonic check).
function drawHarmonics(t) {
  const checks = t.harmonic_check || [];
  const xs = [...new Set(checks.flatMap((c) => c.orders.map((n) => 60 * c.frequency_hz / n)))].sort((a, b) => a - b);
  if (!xs.length) { plot("c-harmonics", "", [], []); $("c-harmonics").textContent = "harmonic check: no cam order meets a mode in the range"; return; }
  plot("c-harmonics", "harmonic check: the cam order meeting each mode (held) at each speed", xs,
    checks.map((c) => {
      const at = new Map(c.orders.map((n) => [60 * c.frequency_hz / n, n]));
      return {label: `${fmt(c.frequency_hz, 5)} Hz`, y: xs.map((x) => at.has(x) ? at.get(x) : null)};
    }), {xlabel: "speed (rpm)", ylabel: "cam order", points: true, lines: false});
}

function drawTrainSpeeds(t) {
  const rows = t.speeds || [];
  const table = $("train-speeds");
  if (!rows.length) { table.innerHTML = "<thead></thead><tbody></tbody>"; return; }
  // every value of a row, a table of them (per body) spread over its keys
  const columns = Object.entries(rows[0]).flatMap(([k, v]) =>
    v !== null && typeof v === "object" && !Array.isArray(v) ? Object.keys(v).map((b) => [k, b]) : [[k, null]]);
  const value = (row, [k, b]) => b === null ? row[k] : (row[k] || {})[b];
  table.querySelector("thead").innerHTML =
    `<tr>${columns.map(([k, b]) => `<th>${b === null ? k : `${k}: ${b}`}</th>`).join("")}</tr>`;
  table.querySelector("tbody").innerHTML = rows.map((row) => `<tr>${columns.map((c) => {
    const v = value(row, c);
    return `<td>${typeof v === "number" ? fmt(v, 5) : v === null || v === undefined ? "-" : JSON.stringify(v)}</td>`;
  }).join("")}</tr>`).join("");
}

// ---- the flexible arm: [arm] -----------------------------------------------------------
// A swinging roller follower's arm as a beam (camjax.program.Arm), its bodies the chain's.
// Its fields come from the server (GET /api/program's `fields.arm`: the library's
// ARM_FIELDS); an empty one is left out (the library's default, said beside it), and the
// table stays until removed, so the library names what it lacks.

const armable = () => { const k = kindOf((model.follower || {}).kind); return k.swinging && k.roller; };

function renderArm() {
  const has = model.arm !== undefined;
  $("arm-box").hidden = !has;
  $("add-arm").hidden = has || !armable();
  if (!has) return;
  renderRecord("arm", fields.arm, true);
  const at = (model.follower || {}).arm_mm;
  $("arm-notes").textContent = `the roller sits ${at === undefined ? "at the follower's arm_mm (empty)" :
    `${at} mm from the pivot (the follower's arm_mm)`}`;
}

// Added: an empty [arm] (the library names its first missing field); a program without a
// chain gets one, its first body the roller (the library names what it lacks, and any
// one-body [follower] field the chain replaces).
function addArm() {
  model.arm = {};
  if (!Array.isArray(model.train)) model.train = [{name: "roller"}];
}

// The report's arm section (camjax.program's arm_section): the first bending mode with the
// cam held, the last body's bending over the speeds (its largest, each cam order's
// amplitude), the cam orders at the range speed nearest the chosen one, and a row per speed.
function drawArm(a) {
  $("arm-report").hidden = !a;
  if (!a) {
    for (const id of ["c-arm-speeds", "c-arm-orders"]) if (charts[id]) { charts[id].destroy(); delete charts[id]; }
    return;
  }
  const rows = a.speeds, rpm = rows.map((s) => s.rpm);
  const near = rows.reduce((best, s) => Math.abs(s.rpm - curves.rpm) < Math.abs(best.rpm - curves.rpm) ? s : best);
  $("arm-facts").innerHTML =
    `<div>first bending mode, cam held: <b id="arm-fundamental" data-hz="${a.fundamental_hz}">${fmt(a.fundamental_hz, 6)}</b> Hz ` +
    `= ${fmt(a.fundamental_rad_s, 6)} rad/s</div>` +
    `<div>bending of <b>${a.body}</b>: its displacement less the rigid swing's</div>`;
  plot("c-arm-speeds", `bending of ${a.body} (mm) vs speed`, rpm, [
    {label: "max |bending|", y: rows.map((s) => s.max_bending_mm)},
    ...a.orders.map((n, j) => ({label: `order ${n}`, y: rows.map((s) => s.bending_harmonics_mm[j]), dash: [4, 3]}))],
  {xlabel: "speed (rpm)", points: true});
  plot("c-arm-orders", `its cam orders at ${fmt(near.rpm, 5)} rpm (mm)`, a.orders.map((_, i) => i + 1),
    [{label: "amplitude", y: near.bending_harmonics_mm}],
    {xlabel: "cam order", points: true, lines: false, xticks: a.orders.map(String)});
  const table = $("arm-speeds");
  table.querySelector("thead").innerHTML =
    `<tr><th rowspan="2">rpm</th><th rowspan="2">first mode, cam orders</th><th rowspan="2">max |bending| mm</th>` +
    `<th colspan="${a.orders.length}">amplitude of each cam order, mm</th></tr>` +
    `<tr>${a.orders.map((n) => `<th>${n}</th>`).join("")}</tr>`;
  table.querySelector("tbody").innerHTML = rows.map((s) => `<tr data-rpm="${s.rpm}"><td>${fmt(s.rpm, 5)}</td>` +
    `<td>${fmt(s.fundamental_orders, 4)}</td><td>${fmt(s.max_bending_mm, 4)}</td>` +
    s.bending_harmonics_mm.map((v) => `<td>${fmt(v, 3)}</td>`).join("") + "</tr>").join("");
}

// ---- undo: the last edits, the program as the page holds it ------------------------------

const UNDO_DEPTH = 50;
const TYPING_MS = 1500;             // keystrokes in one field this close together are one edit
const undoStack = [];               // earlier programs (the model as JSON text), the latest last
let undoShown = null;               // the program the tables show now (JSON text)
let undoField = null, undoAt = 0;   // the field and time of the last remembered edit

function showUndo() {
  $("undo").disabled = !undoStack.length;
  $("undo").title = `undo the last edit (Ctrl+Z); ${undoStack.length} kept`;
}

// A program loaded (the start, Open TOML, a kept design): the edits before it are forgotten.
function forgetEdits() {
  undoStack.length = 0;
  undoShown = JSON.stringify(model);
  undoField = null;
  showUndo();
}

// Called by each edit, after it changed the model: the program before it is kept.
function rememberEdit() {
  const now = JSON.stringify(model);
  if (undoShown === null || now === undoShown) { undoShown = now; return; }
  const typing = lastField !== null && lastField === undoField && Date.now() - undoAt < TYPING_MS;
  if (!typing) {
    undoStack.push(undoShown);
    if (undoStack.length > UNDO_DEPTH) undoStack.shift();
  }
  undoShown = now; undoField = lastField; undoAt = Date.now();
  showUndo();
}

function undo() {
  if (!undoStack.length) return;
  undoShown = undoStack.pop();
  model = JSON.parse(undoShown);
  lastField = null; undoField = null;
  renderEditor();
  showUndo();
  dirty = true;
  clearTimeout(timer);
  timer = setTimeout(send, 0);     // analysed as any edit, without being remembered as one
}

$("undo").addEventListener("click", undo);
// Ctrl+Z (Cmd+Z) undoes a program edit anywhere but in the speed and design fields, whose
// text keeps the browser's own undo.
document.addEventListener("keydown", (e) => {
  if (!(e.ctrlKey || e.metaKey) || e.shiftKey || e.altKey || e.key.toLowerCase() !== "z") return;
  if (e.target.closest && e.target.closest("#range, #chosen, #design")) return;
  e.preventDefault();
  undo();
});

// ---- wiring ----------------------------------------------------------------------------

$("add").addEventListener("click", () => { lastField = null; model.segment.push({angle_deg: 10}); renderEditor(); edited(); });
// a new body at the chain's end, its fields empty: the library names what it needs
$("add-body").addEventListener("click", () => { lastField = null; model.train.push({}); renderEditor(); edited(); });
$("add-arm").addEventListener("click", () => { lastField = null; addArm(); renderEditor(); edited(); });
// removed: a rigid arm; a body still placed on it (at_mm) is named by the library
$("remove-arm").addEventListener("click", () => { lastField = null; delete model.arm; renderEditor(); edited(); });
$("name").addEventListener("input", (e) => { lastField = e.target; model.program = {...(model.program || {}), name: e.target.value}; edited(); });
$("range").addEventListener("input", (e) => { lastField = e.target; rpmText = e.target.value; edited(); });
$("chosen").addEventListener("change", async (e) => {
  lastField = e.target;
  const v = Number(e.target.value);
  chosen = Number.isFinite(v) && e.target.value.trim() !== "" ? v : e.target.value;
  document.body.dataset.busy = "1";
  try { await loadCurves(); } finally { chosen = curves ? curves.rpm : null; document.body.dataset.busy = "0"; }
});
$("angle").addEventListener("input", () => { if (curves) drawProfile(); });
$("open").addEventListener("change", async (e) => {
  const file = e.target.files[0];
  if (!file) return;
  const text = await file.text();
  e.target.value = "";
  document.body.dataset.busy = "1";
  setStatus("computing\u2026", "busy");
  // the server reads the file (the page has no TOML reader): posted as JSON {toml: text}
  const response = await fetch(api("open", {rpm: rpmText}), {method: "POST", body: JSON.stringify({toml: text}),
    headers: {"Content-Type": "application/json"}});
  const answer = await response.json();
  if (!response.ok) { lastField = null; showError(`${file.name}: ${answer.error}`); document.body.dataset.busy = "0"; return; }
  report = answer;
  opened = true;
  const state = await (await fetch(api("program"))).json();
  load(state);
  clearErrors();
  await loadCurves();
  document.body.dataset.busy = "0";
});
$("d-start").addEventListener("click", startDesign);
$("d-keep").addEventListener("click", () => finishDesign("keep"));
$("d-discard").addEventListener("click", () => finishDesign("discard"));
for (const [id, path] of [["save", "program.toml"], ["csv", "profile.csv"], ["dxf", "profile.dxf"]])
  $(id).href = api(path);
window.addEventListener("pagehide", () => navigator.sendBeacon(api("close")));
let resizeTimer = null;
window.addEventListener("resize", () => { clearTimeout(resizeTimer); resizeTimer = setTimeout(draw, 200); });
start();
