// The explorer's page: every change is a request to the API (api.rs), every answer is the
// whole view, which render() draws. The URL's fragment records the history
// (#h=2.0.1&at=3: the indices of the fired steps, the position), so a link reproduces
// a state; #play clicks through the rest of a loaded trace.
"use strict";

const $ = (id) => document.getElementById(id);
let view = null;
// the last request, for play() to wait on
let pending = Promise.resolve(null);

function api(method, path, body) {
  pending = request(method, path, body);
  return pending;
}

async function request(method, path, body) {
  const init = { method };
  if (body !== undefined) {
    init.headers = { "Content-Type": "application/json" };
    init.body = JSON.stringify(body);
  }
  let doc;
  let ok = false;
  try {
    const response = await fetch(path, init);
    ok = response.ok;
    doc = await response.json();
  } catch (e) {
    doc = { error: "the explorer does not answer (" + e + ")" };
  }
  if (!ok) {
    showError(doc.error || "request failed");
    return null;
  }
  showError("");
  render(doc);
  return doc;
}

function showError(message) {
  $("error").textContent = message;
  $("error").hidden = !message;
}

function element(tag, text, className) {
  const e = document.createElement(tag);
  if (text !== undefined) e.textContent = text;
  if (className) e.className = className;
  return e;
}

function render(v) {
  view = v;
  document.title = "bip explore: " + v.system;
  $("system").textContent = v.system;
  $("position").textContent = "step " + v.position + " of " + v.history.length;
  $("back").disabled = v.position === 0;
  $("forward").disabled = v.position === v.history.length;
  $("loaded").hidden = !v.loaded;
  $("loaded").textContent = v.loaded ? "Loaded trace: " + v.loaded + " after " + v.history.length + (v.history.length === 1 ? " step." : " steps.") : "";
  $("deadlock").hidden = v.liveness !== "deadlock";
  $("deadlock").textContent = "deadlock: the system can make no progress, now or after time passes";

  $("liveness").textContent = {
    progress: "a step of the system can be taken",
    "progress after time passes": "a step of the system can be taken once time passes",
    terminal: "no step of the system, and deadlock freedom allows it to end here",
    deadlock: "deadlock",
  }[v.liveness] || v.liveness;

  const next = v.position < v.history.length ? v.history[v.position] : null;
  const enabled = $("enabled");
  enabled.replaceChildren();
  for (const step of v.enabled) {
    const b = element("button", step.label, step.time ? "time" : "");
    if (step.index === next) {
      b.classList.add("next");
      b.title = "the next step of the history";
    }
    b.dataset.index = step.index;
    b.addEventListener("click", () => api("POST", "/api/fire", { index: step.index }));
    const li = element("li");
    li.append(b);
    enabled.append(li);
  }
  if (v.enabled.length === 0) enabled.append(element("li", v.range_error || "none"));

  const held = $("held");
  held.replaceChildren();
  for (const h of v.held) {
    const li = element("li", h.codel);
    const why = element("ul");
    for (const c of h.held_by) why.append(element("li", c));
    li.append(why);
    held.append(li);
  }
  if (v.held.length === 0) held.append(element("li", "no codel is held back"));

  const properties = $("properties");
  properties.replaceChildren();
  for (const p of v.properties) {
    const tr = element("tr");
    tr.title = p.kind + ": " + p.text;
    tr.append(element("td", p.name, "name"), element("td", p.kind), element("td", p.status, p.status.replace(/ /g, "-")));
    properties.append(tr);
  }

  const history = $("history");
  history.replaceChildren();
  const initial = element("li", "initial state", v.position === 0 ? "current" : "");
  initial.addEventListener("click", () => api("POST", "/api/go", { position: 0 }));
  history.append(initial);
  v.steps.forEach((label, k) => {
    const li = element("li", label, k + 1 === v.position ? "current" : k + 1 > v.position ? "future" : "");
    li.addEventListener("click", () => api("POST", "/api/go", { position: k + 1 }));
    history.append(li);
  });

  renderTiming(v.timing);

  const state = $("state");
  state.replaceChildren();
  for (const group of v.state) {
    state.append(element("h3", group.name));
    const table = element("table");
    for (const [name, value] of group.entries) {
      const tr = element("tr");
      tr.append(element("td", name, "name"), element("td", value));
      table.append(tr);
    }
    state.append(table);
  }

  // the SVG is bip's own (bip-picture escapes every text it writes)
  if (v.chart.svg) $("chart").innerHTML = v.chart.svg;
  else $("chart").textContent = v.chart.error;

  const hash = "#h=" + v.history.join(".") + "&at=" + v.position;
  $("link").href = hash;
  window.history.replaceState(null, "", hash);
}

// a timed model's time and tasks (null for an untimed model)
function renderTiming(timing) {
  $("timing").hidden = !timing;
  if (!timing) return;
  $("time").textContent = timing.now.time + " into the " + timing.cycle.time +
    " cycle of the periods (the state holds time modulo it); " + timing.since_start.time +
    " since the initial state along the history. Unit: " + timing.unit + ".";
  const tasks = $("tasks");
  tasks.replaceChildren();
  const head = element("tr");
  for (const h of ["task", "codel", "job"]) head.append(element("th", h));
  tasks.append(head);
  for (const t of timing.tasks) {
    const tr = element("tr");
    const where = [t.cpu, t.core === null ? null : "core " + t.core].filter((x) => x).join(" ");
    const task = element("td", undefined, "task");
    const stage = element("div", t.stage, t.stage === "idle" ? "idle" : t.stage === "running" ? "running" : "");
    stage.title = t.stage_text;
    task.append(element("div", t.name + (where ? " (" + where + ")" : "")), stage);
    // a duration pair is kept on one line
    const codel = element("td", t.codel ? undefined : "–");
    if (t.codel) codel.append(element("div", t.codel.name), element("div", t.codel.elapsed.time + " / " + t.codel.wcet, "times"));
    const job = element("td", t.job ? undefined : "–");
    if (t.job) job.append(element("div", t.job.elapsed.time + " / " + t.job.deadline, "times"));
    const notes = [];
    if (t.job && t.job.past_deadline) notes.push("past its deadline");
    if (t.late) notes.push("late: a period boundary passed while its job ran");
    if (notes.length) {
      job.classList.add("late");
      job.append(element("div", notes.join("; ")));
    }
    tr.append(task, codel, job);
    tasks.append(tr);
  }
}

function parseHash() {
  const fields = new URLSearchParams(location.hash.slice(1));
  const out = { play: fields.has("play") };
  if (fields.has("h")) {
    const h = fields.get("h");
    out.history = h === "" ? [] : h.split(".").map(Number);
    if (fields.has("at")) out.position = Number(fields.get("at"));
  }
  return out;
}

// clicks the enabled step the history goes on with, until its end
async function play() {
  while (view && view.position < view.history.length) {
    const next = document.querySelector("#enabled button.next");
    if (!next) break;
    next.click();
    if (!(await pending)) break;
    await new Promise((done) => setTimeout(done, 300));
  }
}

$("back").addEventListener("click", () => api("POST", "/api/back"));
$("forward").addEventListener("click", () => api("POST", "/api/forward"));
$("play").addEventListener("click", play);
document.addEventListener("keydown", (e) => {
  if (e.target.tagName === "INPUT") return;
  if (e.key === "ArrowLeft" && view && view.position > 0) api("POST", "/api/back");
  if (e.key === "ArrowRight" && view && view.position < view.history.length) api("POST", "/api/forward");
});
$("load").addEventListener("change", async (e) => {
  const file = e.target.files[0];
  if (file) await api("POST", "/api/trace", { trace: await file.text() });
  e.target.value = "";
});

(async () => {
  const link = parseHash();
  if (link.history) await api("POST", "/api/replay", { history: link.history, position: link.position });
  else await api("GET", "/api/state");
  if (link.play) await play();
})();
