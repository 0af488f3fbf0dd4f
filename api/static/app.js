// The certsolve web page: submit jobs, watch them, see their results.
//
// Plain JavaScript, no build step, no dependency. It uses the JSON API like any client:
// GET /v1/robots (the bundled robots), POST /v1/jobs, GET /v1/jobs[/{id}],
// DELETE /v1/jobs/{id}, and the PNG pictures under /v1/jobs/{id}/. An access token, when
// typed, is kept in this page's memory only (not in sessionStorage, where any script of the
// origin could read it later: a reload asks for it again) and sent as "Authorization:
// Bearer ..." with every call (pictures are fetched, not linked, so they carry it too). Every text from the server is
// inserted with textContent, never as HTML.
"use strict";

const POLL_RUNNING_MS = 1500; // the job list while something runs
const POLL_IDLE_MS = 10000; // the job list otherwise (jobs submitted elsewhere)
const POLL_JOB_MS = 1000; // one job's page while it runs
const OLD_TOKEN_KEY = "certsolve.token"; // where earlier versions kept it: removed at start
let accessToken = "";

// -- small helpers --------------------------------------------------------------------------
function $(sel, root) {
  return (root || document).querySelector(sel);
}

function el(tag, attrs, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (v === undefined || v === null || v === false) continue;
    if (k === "class") node.className = v;
    else if (k === "text") node.textContent = v;
    else if (k.startsWith("on")) node.addEventListener(k.slice(2), v);
    else node.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children.flat()) {
    if (c === undefined || c === null || c === false) continue;
    node.append(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return node;
}

function num(x, digits) {
  if (x === null || x === undefined) return "–";
  if (typeof x !== "number") return String(x);
  if (!Number.isFinite(x)) return String(x);
  if (Number.isInteger(x) && Math.abs(x) < 1e15) return String(x);
  const s = x.toPrecision(digits || 6);
  return s.includes("e") ? s : String(Number(s));
}

function fixed(v, decimals) {
  return "(" + (v || []).map((x) => x.toFixed(decimals).replace(/^-(0\.0*)$/, "$1")).join(", ") + ")";
}

function vec(v, digits) {
  return "(" + (v || []).map((x) => num(x, digits)).join(", ") + ")";
}

function age(iso) {
  if (!iso) return "";
  const s = Math.max(0, (Date.now() - Date.parse(iso)) / 1000);
  if (s < 60) return Math.round(s) + " s ago";
  if (s < 3600) return Math.round(s / 60) + " min ago";
  if (s < 86400) return Math.round(s / 3600) + " h ago";
  return Math.round(s / 86400) + " d ago";
}

function duration(s) {
  if (s === null || s === undefined) return "–";
  return s < 10 ? s.toFixed(2) + " s" : s < 120 ? s.toFixed(1) + " s" : (s / 60).toFixed(1) + " min";
}

const FINAL = new Set(["done", "failed", "cancelled"]);

// -- the API ----------------------------------------------------------------------------------
function authHeaders(extra) {
  const h = Object.assign({}, extra || {});
  if (accessToken) h["Authorization"] = "Bearer " + accessToken;
  return h;
}

async function api(method, path, body) {
  const opts = { method, headers: authHeaders(body === undefined ? {} : { "Content-Type": "application/json" }) };
  if (body !== undefined) opts.body = JSON.stringify(body);
  let resp;
  try {
    resp = await fetch(path, opts);
  } catch (err) {
    return { ok: false, status: 0, data: { error: "the service does not answer (" + err.message + ")" } };
  }
  const text = await resp.text();
  let data = null;
  try {
    data = text ? JSON.parse(text) : null;
  } catch (err) {
    data = { error: text.slice(0, 300) };
  }
  if (resp.status === 401) banner("The service wants an access token: type it at the top right.");
  return { ok: resp.ok, status: resp.status, data };
}

function errorText(r) {
  return (r.data && r.data.error) || "HTTP " + r.status;
}

function banner(text) {
  const b = $("#banner");
  b.textContent = text || "";
  b.hidden = !text;
}

// pictures are fetched (with the token) and shown from a blob URL
const blobUrls = [];

async function showPicture(figure, path, alt) {
  const img = el("img", { alt, class: "picture loading" });
  const caption = el("figcaption", { class: "muted", text: "drawing…" });
  figure.replaceChildren(img, caption);
  let resp;
  try {
    resp = await fetch(path, { headers: authHeaders() });
  } catch (err) {
    caption.textContent = "picture unavailable: " + err.message;
    return;
  }
  if (!resp.ok) {
    let msg = "HTTP " + resp.status;
    try {
      msg = (await resp.json()).error || msg;
    } catch (err) {
      /* not JSON */
    }
    img.remove();
    caption.textContent = "no picture: " + msg;
    caption.className = "error";
    return;
  }
  const url = URL.createObjectURL(await resp.blob());
  blobUrls.push(url);
  img.src = url;
  img.classList.remove("loading");
  caption.replaceChildren(el("a", { href: path, target: "_blank", rel: "noopener", text: path }));
}

// -- forms --------------------------------------------------------------------------------------
// Each field names its place in the request ("params.u"); the API's 422 details are shown
// beside the field whose name is the longest prefix of the detail's field.
const CIRCLE_LINE = `// a circle and a line: two certified solutions
Variables
  x in [-10, 10];
  y in [-10, 10];
Constraints
  x^2 + y^2 = 1;
  x - y = 0;
end
`;

const TIMEOUT = { field: "params.timeout", label: "time limit (s)", type: "number", placeholder: "service default" };

const FORMS = [
  {
    kind: "fk",
    title: "Forward kinematics",
    help: "Every equilibrium pose for the control vector u, each certified unique in its box (Merlet 2007).",
    robot: "planar",
    fields: [
      { field: "params.u", label: "control vector u (cm)", type: "list", required: true, hint: "one value per wire" },
      { field: "params.tau_max", label: "τ max (N)", type: "number", placeholder: "the robot's limits", hint: "caps every wire's tension range [τ_min, τ_max]" },
      TIMEOUT,
    ],
  },
  {
    kind: "isotropic-map",
    title: "Isotropic force map",
    help: "The maximum isotropic force over a grid of positions (Krut 2004, Figs. 9 and 10).",
    robot: "krut-3",
    fields: [
      { field: "params.grid", label: "grid: xmin, xmax, ymin, ymax (cm)", type: "list", required: true },
      { field: "params.nx", label: "nx", type: "number", placeholder: "41" },
      { field: "params.ny", label: "ny", type: "number", placeholder: "41" },
      { field: "params.z", label: "z (cm, spatial robots)", type: "number", placeholder: "middle of the domain" },
      { field: "params.orientation", label: "orientation (deg): θ, or yaw, pitch, roll", type: "list", placeholder: "none" },
    ],
  },
  {
    kind: "workspace",
    title: "Certified workspace",
    help: "A paving of a box of positions into parts proven to have an isotropic force ≥ F, proven not to, and boundary boxes narrower than eps.",
    robot: "krut-3",
    fields: [
      { field: "params.min_force", label: "minimum isotropic force F (N)", type: "number", required: true, placeholder: "e.g. 100" },
      { field: "params.box", label: "box: xmin, xmax, ymin, ymax[, zmin, zmax] (cm)", type: "pairs", required: true },
      { field: "params.eps", label: "eps (cm)", type: "number", required: true },
      TIMEOUT,
    ],
  },
  {
    kind: "solve",
    title: "Solve a system",
    help: "Every solution of a square system written in Minibex, each in a box proven to hold exactly one.",
    fields: [
      { field: "system", label: "system (Minibex)", type: "textarea", required: true, value: CIRCLE_LINE },
      { field: "params.eps", label: "eps", type: "number", placeholder: "1e-8" },
      TIMEOUT,
    ],
  },
];

const page = {
  robots: null, // [{name, dof, wires, url}]
  robotsLoaded: false,
  specs: new Map(), // name -> robot file (JSON)
  listTimer: null,
  jobTimer: null,
  jobId: null,
  renderedFinal: null,
  head: null, // the parts of the job page's head (headSkeleton)
};

function fieldId(kind, field) {
  return ("f-" + kind + "-" + field).replace(/[^A-Za-z0-9_-]/g, "-");
}

function buildForms() {
  const tabs = $("#tabs");
  const forms = $("#forms");
  for (const spec of FORMS) {
    tabs.append(
      el("button", { type: "button", role: "tab", "data-kind": spec.kind, onclick: () => selectTab(spec.kind), text: spec.title })
    );
    const form = el("form", { id: "form-" + spec.kind, "data-kind": spec.kind, class: "job-form", novalidate: true, hidden: true });
    form.append(el("p", { class: "muted", text: spec.help }));
    if (spec.robot) form.append(robotField(spec));
    for (const f of spec.fields) form.append(inputField(spec.kind, f));
    form.append(
      el("p", { class: "form-error error", role: "alert", hidden: true }),
      el("div", { class: "actions" }, el("button", { type: "submit", class: "primary", text: "Submit " + spec.kind + " job" }))
    );
    form.addEventListener("submit", (ev) => {
      ev.preventDefault();
      submit(spec, form);
    });
    forms.append(form);
  }
  selectTab(sessionStorage.getItem("certsolve.tab") || "fk");
}

function selectTab(kind) {
  sessionStorage.setItem("certsolve.tab", kind);
  for (const b of document.querySelectorAll("#tabs button")) b.setAttribute("aria-selected", String(b.dataset.kind === kind));
  for (const f of document.querySelectorAll("#forms form")) f.hidden = f.dataset.kind !== kind;
}

function wrap(kind, field, label, control, hint) {
  return el(
    "div",
    { class: "field", "data-field": field },
    el("label", { for: fieldId(kind, field), text: label }),
    control,
    hint ? el("small", { class: "muted", text: hint }) : null,
    el("span", { class: "error field-error", role: "alert" })
  );
}

function inputField(kind, f) {
  const id = fieldId(kind, f.field);
  let control;
  if (f.type === "textarea") {
    control = el("textarea", { id, name: f.field, rows: 10, spellcheck: "false" });
    control.value = f.value || "";
  } else {
    control = el("input", { id, name: f.field, type: "text", placeholder: f.placeholder || (f.required ? "required" : ""), autocomplete: "off" });
  }
  control.dataset.type = f.type;
  control.addEventListener("input", () => {
    control.dataset.touched = "1";
  });
  return wrap(kind, f.field, f.label, control, f.hint);
}

function robotField(spec) {
  const id = fieldId(spec.kind, "robot");
  const select = el("select", { id, name: "robot" }, el("option", { value: "", text: "loading the bundled robots…" }));
  const file = el("input", { type: "file", accept: ".json,application/json", name: "robot-file", hidden: true });
  const info = el("small", { class: "muted robot-info" });
  select.addEventListener("change", () => {
    file.hidden = select.value !== "@file";
    if (select.value === "@file") file.click();
    else robotChosen(spec, select.closest("form"));
  });
  file.addEventListener("change", () => robotChosen(spec, select.closest("form")));
  const box = wrap(spec.kind, "robot", "robot", select, null);
  box.insertBefore(file, box.querySelector(".field-error"));
  box.insertBefore(info, box.querySelector(".field-error"));
  return box;
}

function fillRobots(robots) {
  for (const spec of FORMS) {
    if (!spec.robot) continue;
    const form = $("#form-" + spec.kind);
    const select = form.querySelector("select[name=robot]");
    select.replaceChildren();
    for (const r of robots) {
      select.append(el("option", { value: r.name, text: `${r.name} (dof ${r.dof}, ${r.wires} wires)` }));
    }
    select.append(el("option", { value: "@file", text: "upload a robot file (JSON)…" }));
    select.value = robots.some((r) => r.name === spec.robot) ? spec.robot : robots.length ? robots[0].name : "@file";
    robotChosen(spec, form);
  }
}

async function robotSpec(name) {
  if (!page.specs.has(name)) {
    const r = await api("GET", "v1/robots/" + encodeURIComponent(name));
    if (!r.ok) throw new Error(errorText(r));
    page.specs.set(name, r.data);
  }
  return page.specs.get(name);
}

// The robot of a form: {robot} with the parsed file, or {error} naming the problem.
async function formRobot(form) {
  const select = form.querySelector("select[name=robot]");
  if (select.value !== "@file") {
    try {
      return { robot: await robotSpec(select.value) };
    } catch (err) {
      return { error: "robot: " + err.message };
    }
  }
  const file = form.querySelector("input[name=robot-file]").files[0];
  if (!file) return { error: "robot: choose a robot file (JSON)" };
  const text = await file.text();
  try {
    return { robot: JSON.parse(text), file: file.name };
  } catch (err) {
    return { error: `robot: ${file.name} is not JSON (${err.message})` };
  }
}

async function robotChosen(spec, form) {
  const info = form.querySelector(".robot-info");
  clearErrors(form);
  const got = await formRobot(form);
  if (got.error) {
    info.textContent = "";
    if (form.querySelector("select[name=robot]").value === "@file" && form.querySelector("input[name=robot-file]").files[0]) {
      showErrors(form, [{ field: "robot", text: got.error }]);
    }
    return;
  }
  const robot = got.robot;
  const wires = Array.isArray(robot.wires) ? robot.wires : [];
  info.textContent = `${robot.name || got.file || "robot"}: dof ${robot.dof}, ${wires.length} wires`;
  prefill(spec.kind, form, robot, wires);
}

// sensible starting values from the robot, in fields the user has not typed in
function prefill(kind, form, robot, wires) {
  const set = (field, value) => {
    const input = form.querySelector(`[name="${field}"]`);
    if (input && !input.dataset.touched) input.value = value;
  };
  const anchors = wires.map((w) => w.base).filter(Array.isArray);
  if (!anchors.length) return;
  const dim = anchors[0].length;
  const lo = [], hi = [];
  for (let a = 0; a < dim; a++) {
    lo.push(Math.min(...anchors.map((p) => p[a])));
    hi.push(Math.max(...anchors.map((p) => p[a])));
  }
  if (kind === "fk") set("params.u", wires.map(() => 0).join(", "));
  if (kind === "isotropic-map") set("params.grid", [lo[0], hi[0], lo[1], hi[1]].map((x) => num(x)).join(", "));
  if (kind === "workspace") {
    const box = [];
    for (let a = 0; a < dim; a++) box.push(num(lo[a]), num(hi[a]));
    set("params.box", box.join(", "));
    set("params.eps", num(Math.max(...hi.map((h, a) => h - lo[a])) / 50, 2));
  }
}

// a value as typed -> JSON; what does not parse is sent as typed, so the API names it
function parseValue(type, text) {
  const t = text.trim();
  if (type === "textarea") return text;
  if (t === "") return undefined;
  const one = (s) => (s !== "" && Number.isFinite(Number(s)) ? Number(s) : s);
  if (type === "number") return one(t);
  const items = t.split(/[\s,;]+/).filter((s) => s !== "").map(one);
  if (type === "list") return items;
  if (type === "pairs") {
    const pairs = [];
    for (let i = 0; i < items.length; i += 2) pairs.push(items.slice(i, i + 2));
    return pairs;
  }
  return t;
}

function setPath(obj, path, value) {
  const keys = path.split(".");
  let o = obj;
  for (const k of keys.slice(0, -1)) o = o[k] = o[k] || {};
  o[keys[keys.length - 1]] = value;
}

function clearErrors(form) {
  for (const e of form.querySelectorAll(".field-error")) e.textContent = "";
  for (const f of form.querySelectorAll(".field.invalid")) f.classList.remove("invalid");
  const fe = form.querySelector(".form-error");
  fe.textContent = "";
  fe.hidden = true;
}

// errors: [{field, text}]; each goes beside the field with the longest matching name
function showErrors(form, errors) {
  const fields = [...form.querySelectorAll(".field")];
  const rest = [];
  for (const e of errors) {
    let best = null;
    for (const f of fields) {
      const name = f.dataset.field;
      if ((e.field === name || e.field.startsWith(name + ".")) && (!best || name.length > best.dataset.field.length)) best = f;
    }
    if (!best) {
      rest.push(e.text);
      continue;
    }
    best.classList.add("invalid");
    const span = best.querySelector(".field-error");
    span.textContent = span.textContent ? span.textContent + "; " + e.text : e.text;
  }
  if (rest.length) {
    const fe = form.querySelector(".form-error");
    fe.textContent = rest.join("; ");
    fe.hidden = false;
  }
}

async function submit(spec, form) {
  clearErrors(form);
  const button = form.querySelector("button[type=submit]");
  const body = { kind: spec.kind };
  if (spec.robot) {
    const got = await formRobot(form);
    if (got.error) {
      showErrors(form, [{ field: "robot", text: got.error }]);
      return;
    }
    body.robot = got.robot;
  }
  for (const f of spec.fields) {
    const input = form.querySelector(`[name="${f.field}"]`);
    let value = parseValue(f.type, input.value);
    if (value === undefined && f.required) value = f.type === "number" ? null : [];
    if (value !== undefined) setPath(body, f.field, value);
  }
  if (!body.params) body.params = {};
  button.disabled = true;
  const r = await api("POST", "v1/jobs", body);
  button.disabled = false;
  if (r.status === 202) {
    location.hash = "#/jobs/" + r.data.id;
    return;
  }
  const details = (r.data && r.data.detail) || [];
  if (r.status === 422 && details.length) {
    showErrors(form, details.map((d) => ({ field: d.field || "", text: `${d.field}: ${d.msg}` })));
  } else {
    showErrors(form, [{ field: "", text: errorText(r) }]);
  }
}

// -- the job list ---------------------------------------------------------------------------
function progressText(job) {
  const p = job.progress || {};
  const parts = [];
  const names = ["boxes", "solutions", "undecided", "pending", "inside", "outside", "boundary"];
  for (const k of names) if (typeof p[k] === "number") parts.push(`${k} ${num(p[k])}`);
  if (p.stopped_by) parts.push("stopped by " + p.stopped_by);
  return parts.join(" · ");
}

// the job's status, and beside a finished one "incomplete" when its verdict is not a
// proof (on the job's page, `v` from verdict()), or, in the list (which has no results),
// when its last progress left boxes pending or undecided or was stopped; a workspace's
// undecided boxes are its boundary boxes, part of a complete paving
function statusBadge(job, v) {
  let word = job.status;
  if (job.cancel_requested && !FINAL.has(job.status)) word = "cancelling";
  const p = job.progress || {};
  const undecided = job.kind === "workspace" ? 0 : p.undecided;
  let worry = FINAL.has(job.status) && (p.pending > 0 || undecided > 0 || !!p.stopped_by);
  if (v) worry = job.status !== "failed" && v.cls === "warn";
  return el(
    "span",
    {},
    el("span", { class: "badge status-" + job.status, text: word }),
    worry ? el("span", { class: "badge warn", text: "incomplete" }) : ""
  );
}

// the number of `name` ("pending" or "undecided") boxes of a search result: the lists
// hold hulls of groups of boxes, `name`_total counts the boxes themselves
function boxCount(result, name) {
  const total = result[name + "_total"];
  if (typeof total === "number") return total;
  return (result.truncated && result.truncated[name]) || (result[name] || []).length;
}

async function cancelJob(id, button) {
  if (button) button.disabled = true;
  const r = await api("DELETE", "v1/jobs/" + encodeURIComponent(id));
  if (button) button.disabled = false;
  if (!r.ok && r.status !== 409) banner("cancel failed: " + errorText(r));
  refresh();
}

// Rows are updated in place, and a row's cancel button is only replaced when the job
// stops being cancellable: a click is never lost to a refresh.
function jobRow(job) {
  const tr = el(
    "tr",
    { "data-id": job.id },
    el("td", {}, el("a", { href: "#/jobs/" + job.id, class: "mono", text: job.id.slice(0, 10) })),
    el("td", { text: job.kind }),
    el("td"),
    el("td", { class: "progress-cell" }),
    el("td"),
    el("td")
  );
  return updateRow(tr, job);
}

function updateRow(tr, job) {
  const active = !FINAL.has(job.status);
  const [, , status, progress, when, action] = tr.children;
  tr.dataset.status = job.status;
  status.replaceChildren(statusBadge(job));
  progress.replaceChildren(job.status === "running" ? el("span", { class: "spinner" }) : "", progressText(job));
  when.title = job.created_at;
  when.textContent = age(job.created_at);
  const cancellable = active && !job.cancel_requested;
  if (cancellable !== Boolean(action.firstChild)) {
    action.replaceChildren(
      cancellable ? el("button", { type: "button", class: "cancel", onclick: (ev) => cancelJob(job.id, ev.target), text: "cancel" }) : ""
    );
  }
  return tr;
}

async function loadJobs() {
  const r = await api("GET", "v1/jobs?limit=50");
  if (!r.ok) {
    $("#jobs-note").textContent = "(" + errorText(r) + ")";
    return null;
  }
  const items = r.data.items || [];
  const body = $("#job-table tbody");
  const rows = new Map([...body.children].map((tr) => [tr.dataset.id, tr]));
  const order = items.map((job) => (rows.has(job.id) ? updateRow(rows.get(job.id), job) : jobRow(job)));
  const same = order.length === body.children.length && order.every((tr, i) => body.children[i] === tr);
  if (!same) body.replaceChildren(...order);
  $("#jobs-empty").hidden = items.length > 0;
  const running = items.filter((j) => !FINAL.has(j.status)).length;
  $("#jobs-note").textContent = running ? `(${running} queued or running, refreshed every ${POLL_RUNNING_MS / 1000} s)` : "";
  return running;
}

function schedule(kind, fn, ms) {
  clearTimeout(page[kind]);
  page[kind] = setTimeout(fn, ms);
}

async function refresh() {
  if ($("#home-view").hidden) return;
  let running = 0;
  if (!document.hidden) running = await loadJobs();
  schedule("listTimer", refresh, running ? POLL_RUNNING_MS : POLL_IDLE_MS);
}

// -- one job ------------------------------------------------------------------------------------
function kv(rows) {
  return el(
    "table",
    { class: "kv" },
    rows.filter((r) => r).map(([k, v]) => el("tr", {}, el("th", { text: k }), el("td", {}, v)))
  );
}

// The head of a job's page is built once per job and then updated, so that its cancel
// button stays the same element while the job runs.
function headSkeleton(id) {
  const head = $("#job-head");
  const parts = {
    id,
    badge: el("span"),
    text: el("span"),
    bar: el("progress", { max: 1, value: 0 }),
    used: el("small", { class: "muted" }),
    cancel: el("button", { type: "button", class: "cancel", text: "cancel this job" }),
    note: el("p", { class: "muted", text: "cancel requested: the job stops within about a second", hidden: true }),
    facts: el("div"),
  };
  parts.cancel.addEventListener("click", () => cancelJob(id, parts.cancel).then(loadJob));
  parts.running = el("div", { class: "running" }, el("span", { class: "spinner" }), parts.text, el("div", { class: "bar" }, parts.bar, parts.used), parts.cancel, parts.note);
  head.replaceChildren(el("h2", {}, el("span", { text: "job " }), el("span", { class: "mono", text: id }), " ", parts.badge), parts.running, parts.facts);
  page.head = parts;
  return parts;
}

function renderHead(job, v) {
  const h = page.head && page.head.id === job.id ? page.head : headSkeleton(job.id);
  const lim = job.limits || {};
  $("#job-head h2 span").textContent = job.kind + " job ";
  h.badge.replaceWith((h.badge = statusBadge(job, v)));
  h.running.hidden = FINAL.has(job.status);
  if (!FINAL.has(job.status)) {
    const used = job.elapsed || 0;
    h.text.textContent = job.status === "queued" ? "waiting for a worker…" : "searching… " + progressText(job);
    h.bar.max = lim.timeout || 1;
    h.bar.value = Math.min(used, lim.timeout || used);
    h.used.textContent = `time used: ${duration(used)} of the ${duration(lim.timeout)} limit`;
    h.cancel.hidden = job.cancel_requested;
    h.note.hidden = !job.cancel_requested;
  }
  h.facts.replaceChildren(
    kv([
      ["created", `${job.created_at} (${age(job.created_at)})`],
      job.started_at ? ["started", job.started_at] : null,
      job.finished_at ? ["finished", job.finished_at] : null,
      ["run time", duration(job.elapsed)],
      ["limits", `time ${duration(lim.timeout)}, ${num(lim.max_boxes)} boxes, ${num(lim.memory_mb)} MiB`],
      ["attempts", `${job.attempts} of ${job.max_attempts}`],
      FINAL.has(job.status) && progressText(job) ? ["last progress", progressText(job)] : null,
      job.error ? ["error", el("span", { class: "error", text: job.error })] : null,
    ])
  );
}

// what a result proves, in words; never "success" for a search that left something open
function verdict(job, result) {
  if (job.status === "failed") return { cls: "bad", text: "failed: " + (job.error || "no reason given") };
  if (!result) return { cls: "warn", text: `${job.status}: no result` + (job.error ? ` (${job.error})` : "") };
  const cancelled = job.status === "cancelled" ? "cancelled: partial result. " : "";
  const cut = result.truncated ? ` Only part of long lists is stored (${Object.entries(result.truncated).map(([k, n]) => `${k}: ${n}`).join(", ")}).` : "";
  if (job.kind === "fk" || job.kind === "solve") {
    const what = job.kind === "fk" ? "certified pose(s)" : "certified solution(s)";
    const n = (result.solutions || []).length;
    const und = boxCount(result, "undecided");
    const pen = boxCount(result, "pending");
    const stop = result.stats && result.stats.stopped_by ? ` (stopped by ${result.stats.stopped_by})` : "";
    if (result.status === "complete" && !und && !cancelled)
      return { cls: "ok", text: `complete: ${n} ${what}; there is no other in the search domain.${cut}` };
    if (result.status === "complete")
      return { cls: "warn", text: `${cancelled}search complete but ${und} undecided box(es): ${n} ${what}, and a solution may hide in each undecided box.${cut}` };
    return { cls: "warn", text: `${cancelled}incomplete${stop}: ${n} ${what} so far, ${und} undecided and ${pen} pending box(es); there may be more.${cut}` };
  }
  if (job.kind === "workspace") {
    const c = result.counts || {};
    if (result.status === "complete" && !cancelled)
      return { cls: "ok", text: `complete: every box is proven inside or outside, or is a boundary box narrower than eps (${num(c.boundary)}).${cut}` };
    return { cls: "warn", text: `${cancelled}incomplete (${result.status}): ${num(c.pending)} box(es) not processed.${cut}` };
  }
  if (job.kind === "isotropic-map") {
    const s = result.summary || {};
    return { cls: "neutral", text: `${cancelled}map of ${num(s.poses)} grid points (values at the points, not a certified enclosure).${cut}` };
  }
  return { cls: job.status === "done" ? "neutral" : "warn", text: cancelled + job.status };
}

function picturePath(id, name) {
  return `v1/jobs/${encodeURIComponent(id)}/${name}`;
}

function figure(path, alt) {
  const f = el("figure", { class: "picture-box" });
  showPicture(f, path, alt);
  return f;
}

// A job's picture beside the table of its facts (maps, pavings, paths).
function pictureWithFacts(job, name, alt, rows) {
  return el("div", { class: "pose-body" }, figure(picturePath(job.id, name), alt), kv(rows));
}

function renderFk(job, r, out) {
  const poses = r.solutions || [];
  out.append(el("p", {}, `formulation ${r.formulation}, u = ${vec(r.u, 6)}, ${num((r.stats || {}).boxes)} boxes`));
  if (poses.length > 1) out.append(el("h3", { text: "all poses" }), figure(picturePath(job.id, "poses.png"), "all poses"));
  poses.forEach((p, k) => {
    const m = (p.tau || []).length;
    const wires = [];
    for (let i = 0; i < m; i++) wires.push(el("tr", {}, el("td", { text: String(i + 1) }), el("td", { text: num(p.tau[i], 5) }), el("td", { text: num(p.rho[i], 6) })));
    const angles = (p.euler || []).length === 1 ? "θ (deg)" : "yaw, pitch, roll (deg)";
    out.append(
      el(
        "article",
        { class: "pose", "data-pose": k },
        el("h3", { text: `pose ${k + 1} of ${poses.length}` + (p.stability ? ` (${p.stability})` : "") }),
        el(
          "div",
          { class: "pose-body" },
          figure(picturePath(job.id, `poses/${k}.png`), `pose ${k + 1}`),
          el(
            "div",
            {},
            kv([
              ["position (cm)", vec(p.position, 7)],
              [angles, fixed(p.euler || [], 4)],
              ["certificate", `${p.certificate}` + (p.verified === true ? ", verified with mpmath" : p.verified === false ? ", NOT verified" : "")],
              ["stability", p.stability ? `${p.stability}, smallest Hessian eigenvalue in [${(p.eig_min || []).map((v, i) => (v === null ? (i ? "∞" : "−∞") : num(v, 6))).join(", ")}]` : "not given"],
              ["existence box", `${(p.box || []).length} variables, widths ≤ ${num(Math.max(...(p.box || [[0, 0]]).map((b) => b[1] - b[0])), 2)}`],
              p.position_lo ? ["position bounds (cm)", p.position_lo.map((v, c) => `[${num(v, 7)}, ${num(p.position_hi[c], 7)}]`).join(", ")] : null,
            ]),
            el("table", { class: "tensions" }, el("thead", {}, el("tr", {}, el("th", { text: "wire" }), el("th", { text: "tension τ (N)" }), el("th", { text: "length ρ (cm)" }))), el("tbody", {}, wires))
          ),
          p.platform_points_lo && p.platform_points_lo.length ? poseBoxes(p) : null
        )
      )
    );
  });
  boxesNote(r, out);
}

// -- the pose boxes of a robot with tolerances ---------------------------------------------------
// The SVG namespace (the W3C's name for it, not a URL the page loads).
const SVG_NS = "http://www.w3.org/2000/svg";

function svgEl(tag, attrs, ...children) {
  const node = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === "text") node.textContent = v;
    else node.setAttribute(k, String(v));
  }
  for (const c of children.flat()) if (c) node.append(c);
  return node;
}

// Convex hull (Andrew's monotone chain) of 2-D points, counter-clockwise.
function hull2d(points) {
  const p = points.slice().sort((a, b) => a[0] - b[0] || a[1] - b[1]);
  if (p.length < 3) return p;
  const cross = (o, a, b) => (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  const half = (pts) => {
    const h = [];
    for (const q of pts) {
      while (h.length >= 2 && cross(h[h.length - 2], h[h.length - 1], q) <= 0) h.pop();
      h.push(q);
    }
    h.pop();
    return h;
  };
  return half(p).concat(half(p.slice().reverse()));
}

// A drawing scale for boxes much smaller than the platform: 1, 2, 5, 10, 20, ... so that
// the widest box is at least a tenth of the platform's extent.
function enlargement(span, widest) {
  let f = 1;
  for (let k = 0; widest * f < 0.1 * span && k < 30; k++) f *= [2, 2.5, 2][k % 3];
  return f;
}

// One projection of the attachments' bounds: a rectangle per attachment (its bounds over
// every robot of the set, enlarged ``mag`` times about their centre) and the platform's
// outline through the centres; equal scales on both axes, the second axis upwards.
function projection(lo, hi, a, b, names, mag) {
  const size = 240;
  const pad = 28;
  const c = lo.map((l, i) => [0.5 * (l[a] + hi[i][a]), 0.5 * (l[b] + hi[i][b])]);
  const r = lo.map((l, i) => [0.5 * mag * (hi[i][a] - l[a]), 0.5 * mag * (hi[i][b] - l[b])]);
  const xs = c.flatMap((q, i) => [q[0] - r[i][0], q[0] + r[i][0]]);
  const ys = c.flatMap((q, i) => [q[1] - r[i][1], q[1] + r[i][1]]);
  const x0 = Math.min(...xs);
  const y0 = Math.min(...ys);
  const wx = Math.max(...xs) - x0;
  const wy = Math.max(...ys) - y0;
  const span = Math.max(wx, wy) || 1;
  const s = (size - 2 * pad) / span;
  const X = (x) => pad + 0.5 * (span - wx) * s + (x - x0) * s; // centred in the panel
  const Y = (y) => size - pad - 0.5 * (span - wy) * s - (y - y0) * s;
  const rects = lo.map((l, i) => {
    const h = hi[i];
    return svgEl(
      "rect",
      { class: "pp-box", "data-wire": i + 1, x: X(c[i][0] - r[i][0]), y: Y(c[i][1] + r[i][1]), width: Math.max(2 * r[i][0] * s, 0.5), height: Math.max(2 * r[i][1] * s, 0.5) },
      svgEl("title", { text: `wire ${i + 1}: ${names[0]} [${num(l[a], 7)}, ${num(h[a], 7)}], ${names[1]} [${num(l[b], 7)}, ${num(h[b], 7)}] cm` })
    );
  });
  const outline = hull2d(c).map((q) => `${X(q[0]).toFixed(2)},${Y(q[1]).toFixed(2)}`).join(" ");
  return svgEl(
    "svg",
    { class: "pose-boxes", viewBox: `0 0 ${size} ${size}`, width: size, height: size, role: "img", "aria-label": `attachment bounds, ${names[0]}-${names[1]} projection` },
    svgEl("polygon", { class: "pp-hull", points: outline }),
    rects,
    svgEl("text", { class: "pp-axis", x: size / 2, y: size - 6, "text-anchor": "middle", text: `${names[0]} (${num(span, 3)} cm across)` }),
    svgEl("text", { class: "pp-axis", x: 10, y: size / 2, transform: `rotate(-90 10 ${size / 2})`, "text-anchor": "middle", text: names[1] })
  );
}

function poseBoxes(p) {
  const lo = p.platform_points_lo;
  const hi = p.platform_points_hi;
  const d = lo[0].length;
  const views = d === 3 ? [[0, 1, ["x", "y"]], [0, 2, ["x", "z"]]] : [[0, 1, ["x", "y"]]];
  const widest = Math.max(...lo.flatMap((l, i) => l.map((v, c) => hi[i][c] - v)));
  const ext = Math.max(...lo[0].map((_, c) => Math.max(...hi.map((h) => h[c])) - Math.min(...lo.map((l) => l[c]))));
  const mag = enlargement(ext, widest);
  const drawn = mag === 1 ? "" : `, drawn ${num(mag)}× enlarged about their centres`;
  return el(
    "figure",
    { class: "picture-box pose-set", "data-enlarged": mag },
    views.map(([a, b, names]) => projection(lo, hi, a, b, names, mag)),
    el("figcaption", { class: "muted", text: `every robot of the set: the bounds of each attachment (boxes, widest side ${num(widest, 3)} cm${drawn}) and the platform through their centres` })
  );
}

function boxesNote(r, out) {
  const und = r.undecided || [];
  if (und.length) {
    const groups = und.length < boxCount(r, "undecided") ? ` in ${und.length} group(s)` : "";
    out.append(el("h3", { text: `${num(boxCount(r, "undecided"))} undecided box(es)${groups}` }));
    out.append(el("ul", {}, und.slice(0, 20).map((u) => el("li", { text: (u.reason || "undecided") + (u.box ? " " + JSON.stringify(u.box.map((b) => b.map((x) => Number(num(x, 6))))) : "") }))));
  }
  const pen = boxCount(r, "pending");
  if (pen) out.append(el("p", { class: "warn-text", text: `${num(pen)} pending box(es): the search stopped before looking into them.` }));
}

function renderSolve(job, r, out) {
  const vars = r.variables || [];
  const head = el("tr", {}, el("th", { text: "#" }), vars.map((v) => el("th", { text: v })), el("th", { text: "box width" }), el("th", { text: "certificate" }));
  const rows = (r.solutions || []).map((s, k) =>
    el(
      "tr",
      {},
      el("td", { text: String(k + 1) }),
      (s.midpoint || []).map((x) => el("td", { class: "mono", text: num(x, 12) })),
      el("td", { text: num(Math.max(...s.box.map((b) => b[1] - b[0])), 2) }),
      el("td", { text: s.certificate + (s.verified === true ? " (verified)" : "") })
    )
  );
  out.append(el("table", { class: "solutions" }, el("thead", {}, head), el("tbody", {}, rows)));
  const st = r.stats || {};
  out.append(el("p", { class: "muted", text: `${num(st.boxes)} boxes, ${num(st.bisections)} bisections, ${duration(st.time)}` }));
  boxesNote(r, out);
}

function renderMap(job, r, out) {
  const s = r.summary || {};
  out.append(
    pictureWithFacts(job, "map.png", "isotropic force map", [
      ["robot", r.robot],
      ["grid", `${(r.xs || []).length} × ${(r.ys || []).length} points` + (r.z !== null && r.z !== undefined ? `, z = ${num(r.z)} cm` : "")],
      ["inside / outside / degenerate", `${num(s.inside)} / ${num(s.outside)} / ${num(s.degenerate)}`],
      ["maximum", s.max === null ? "–" : `${num(s.max, 6)} N at ${vec(s.argmax, 6)}`],
      ["inside area (estimate)", s.inside_area_estimate === undefined ? "–" : `${num(s.inside_area_estimate, 5)} cm²`],
    ])
  );
}

function renderWorkspace(job, r, out) {
  const c = r.counts || {};
  out.append(
    pictureWithFacts(job, "paving.png", "certified paving", [
      ["robot", r.robot],
      ["required force", `${num(r.min_force)} N`],
      ["status", r.status],
      ["boxes inside / outside / boundary / pending", `${num(c.inside)} / ${num(c.outside)} / ${num(c.boundary)} / ${num(c.pending)}`],
      ["proven inside", `${num(r.inside_measure, 5)} ${r.unit} (${num(100 * r.inside_share, 4)} % of the box)`],
      ["boxes processed", num(r.boxes)],
    ])
  );
}

function renderTrajectory(job, r, out) {
  const st = r.stats || {};
  out.append(
    pictureWithFacts(job, "path.png", "pose and tensions along the path", [
      ["robot", r.robot],
      ["status", r.status],
      ["certified and joined", `${num(r.certified)} step(s)`],
      ["lost at", r.lost_at === null || r.lost_at === undefined ? "–" : `step ${r.lost_at}: ${r.reason}`],
      ["chunks proven / split", `${num(st.chunks)} / ${num(st.chunk_failures)}`],
      ["time", duration(st.time)],
    ])
  );
}

const RENDER = { fk: renderFk, solve: renderSolve, "isotropic-map": renderMap, workspace: renderWorkspace, trajectory: renderTrajectory };

function renderResult(job, v) {
  const out = $("#job-result");
  const r = job.result;
  out.replaceChildren(el("p", { class: "verdict " + v.cls, id: "verdict", text: v.text }));
  if (r && RENDER[job.kind]) RENDER[job.kind](job, r, out);
  else if (r) out.append(el("pre", { text: JSON.stringify(r, null, 1).slice(0, 5000) }));
  out.hidden = false;
  const raw = $("#job-raw");
  if (r) {
    const text = JSON.stringify(r, null, 1);
    $("#raw-json").textContent = text.length > 300000 ? text.slice(0, 300000) + "\n… (cut: open the JSON for all of it)" : text;
    $("#raw-link").href = `v1/jobs/${encodeURIComponent(job.id)}/result`;
  }
  raw.hidden = !r;
}

async function loadJob() {
  const id = page.jobId;
  if (!id) return;
  if (document.hidden) {
    schedule("jobTimer", loadJob, POLL_JOB_MS);
    return;
  }
  const r = await api("GET", "v1/jobs/" + encodeURIComponent(id));
  if (id !== page.jobId) return;
  if (!r.ok) {
    page.head = null;
    $("#job-head").replaceChildren(el("h2", {}, "job ", el("span", { class: "mono", text: id })), el("p", { class: "error", text: errorText(r) }));
    return;
  }
  const job = r.data;
  const v = FINAL.has(job.status) ? verdict(job, job.result) : null;
  renderHead(job, v);
  if (FINAL.has(job.status)) {
    if (page.renderedFinal !== id) {
      page.renderedFinal = id;
      renderResult(job, v);
    }
    return;
  }
  schedule("jobTimer", loadJob, POLL_JOB_MS);
}

// -- routing --------------------------------------------------------------------------------------
function route() {
  clearTimeout(page.listTimer);
  clearTimeout(page.jobTimer);
  while (blobUrls.length) URL.revokeObjectURL(blobUrls.pop());
  banner("");
  const m = location.hash.match(/^#\/jobs\/([A-Za-z0-9_-]+)$/);
  $("#home-view").hidden = !!m;
  $("#job-view").hidden = !m;
  if (m) {
    page.jobId = m[1];
    page.renderedFinal = null;
    page.head = null;
    $("#job-head").replaceChildren(el("p", { class: "muted", text: "loading…" }));
    $("#job-result").hidden = true;
    $("#job-raw").hidden = true;
    $("#raw-details").open = false;
    document.title = "certsolve: job " + m[1].slice(0, 10);
    loadJob();
  } else {
    page.jobId = null;
    document.title = "certsolve";
    refresh();
  }
}

async function start() {
  const token = $("#token");
  sessionStorage.removeItem(OLD_TOKEN_KEY);
  token.value = "";
  token.addEventListener("change", () => {
    accessToken = token.value.trim();
    route();
    if (!page.robotsLoaded) loadRobots();
  });
  buildForms();
  window.addEventListener("hashchange", route);
  document.addEventListener("visibilitychange", () => {
    if (document.hidden) return;
    if (!page.jobId) refresh();
    else if (page.renderedFinal !== page.jobId) loadJob();
  });
  route();
  await loadRobots();
}

// the bundled robots of the forms (again once a token is typed, if they were refused)
async function loadRobots() {
  const r = await api("GET", "v1/robots");
  page.robotsLoaded = r.ok;
  if (r.ok) fillRobots(r.data.robots || []);
  else if (r.status !== 401) banner("cannot list the bundled robots: " + errorText(r));
}

document.addEventListener("DOMContentLoaded", start);
