// The HMI page: render the state and history pushed by /events; send commands to /api/*.
// The plots and timeline are plots.js's, the why dialog why.js's (loaded before this file).
"use strict";

const AC = "https://w3id.org/tspace/selfconfig#";
const TOKEN = document.querySelector('meta[name="hmi-token"]').content;
const SPEEDS = { stopped: 0, low: 1, normal: 2, high: 3 };
const cards = new Map(); // robot name -> {card, chart, state}
window.__charts = new Map(); // robot name -> its uPlot chart (read by the browser test)
const history = new Map(); // robot name -> events, oldest first
let lastState = null;
let redrawQueued = false;

function text(value) {
  return value === null || value === undefined || value === "" ? "–" : String(value);
}

function iri(name) {
  return `<${AC}${name}>`;
}

// A triple's N-Triples terms as people read them: ac:robot1, "low".
function short(term) {
  if (term.startsWith(`<${AC}`)) return `ac:${term.slice(AC.length + 1, -1)}`;
  const literal = term.match(/^"(.*)"(\^\^<[^>]*>|@[\w-]+)?$/s);
  return literal ? `"${literal[1]}"` : term;
}

function slug(value) {
  return text(value).toLowerCase().replace(/[^a-z0-9]+/g, "-");
}

// options: strings, or {name, label} objects. The user's choice survives updates.
function fillSelect(select, options, preferred) {
  const pairs = options.map((o) => (typeof o === "string" ? [o, o] : [o.name, o.label]));
  const wanted = JSON.stringify(pairs);
  if (select.dataset.options !== wanted) {
    select.dataset.options = wanted;
    select.replaceChildren(...pairs.map(([value, label]) => new Option(label, value)));
  }
  if (preferred && !select.dataset.touched && pairs.some(([value]) => value === preferred)) {
    select.value = preferred;
  }
}

async function send(card, path, body) {
  const feedback = card.querySelector(".feedback");
  feedback.textContent = "sending…";
  try {
    const response = await fetch(path, {
      method: "POST",
      headers: { "Content-Type": "application/json", "X-HMI-Token": TOKEN },
      body: JSON.stringify(body),
    });
    const answer = await response.json();
    feedback.textContent = response.ok ? "done" : `refused: ${answer.error}`;
  } catch (error) {
    feedback.textContent = `failed: ${error}`;
  }
}

function cardFor(name) {
  let entry = cards.get(name);
  if (entry) return entry;
  const card = document.getElementById("robot-card").content.firstElementChild.cloneNode(true);
  card.dataset.robot = name;
  entry = { card, chart: null, state: null };
  card.querySelector(".assign").addEventListener("submit", (event) => {
    event.preventDefault();
    const task = card.querySelector(".task-select").value;
    const request = { robot: name, task, person: card.querySelector(".person-select").value };
    if (task === "Guiding") request.destination = card.querySelector(".place-select").value;
    send(card, "/api/task", request);
  });
  card.querySelector(".battery-form").addEventListener("submit", (event) => {
    event.preventDefault();
    send(card, "/api/battery", { robot: name, level: card.querySelector(".battery-select").value });
  });
  for (const select of card.querySelectorAll("select")) {
    select.addEventListener("change", () => (select.dataset.touched = "yes"));
  }
  card.querySelector('[data-why="task"]').addEventListener("click", () =>
    why(`Why is ${name}'s task what it is?`, [[iri(name), iri("current_task"), null]]),
  );
  card.querySelector('[data-why="speed"]').addEventListener("click", () => {
    const base = (entry.state?.devices || []).find((d) => d.kind === "MobileBase");
    if (base) why(`Why is ${name}'s speed what it is?`, [[iri(base.name), iri("motion_speed"), null]]);
  });
  document.getElementById("robots").append(card);
  cards.set(name, entry);
  return entry;
}

function renderRobot(robot, state) {
  const entry = cardFor(robot.name);
  entry.state = robot;
  const card = entry.card;
  const battery = robot.charge === null ? text(robot.battery) : `${text(robot.battery)} (${robot.charge}%)`;
  const values = { ...robot, battery, task_type: text(robot.task_type) };
  for (const field of card.querySelectorAll("[data-field]")) {
    field.textContent = text(values[field.dataset.field]);
  }
  showFreshness(card.querySelector('dd[data-field="battery"]'), robot.battery_fresh, "reading");
  card.querySelector(".presence").className = `badge presence ${slug(robot.presence)}`;
  card.querySelector(".presence").hidden = !robot.presence;
  card.querySelector(".site").hidden = !robot.site;
  card.querySelector(".says").hidden = !robot.announcement;
  card.querySelector(".devices tbody").replaceChildren(...robot.devices.map((d) => deviceRow(robot, d)));
  fillSelect(card.querySelector(".task-select"), state.tasks || []);
  fillSelect(card.querySelector(".person-select"), robot.people || []);
  fillSelect(card.querySelector(".place-select"), robot.places || []);
  fillSelect(card.querySelector(".battery-select"), state.levels || [], robot.battery);
}

function deviceRow(robot, device) {
  const row = document.createElement("tr");
  row.dataset.device = device.name;
  const shown = device.name.startsWith(`${robot.name}_`) ? device.name.slice(robot.name.length + 1) : device.name;
  const cells = [["name", shown], ["kind", device.kind], ["mode", device.mode], ["reported", device.reported]];
  for (const [key, value] of cells) {
    const cell = document.createElement("td");
    cell.dataset.field = key;
    cell.textContent = text(value);
    if (key === "mode" || key === "reported") cell.className = `mode ${slug(value)}`;
    if (key === "reported" && device.reported && device.mode && device.reported !== device.mode) {
      cell.classList.add("pending");
      cell.title = "the device has not obeyed yet";
    }
    if (key === "reported") showFreshness(cell, device.reported_fresh, "report");
    row.append(cell);
  }
  const cell = document.createElement("td");
  const button = document.createElement("button");
  button.type = "button";
  button.className = "why-link";
  button.textContent = "why?";
  button.addEventListener("click", () => why(`Why is ${shown} in this mode?`, [[iri(device.name), iri("running_mode"), null]]));
  cell.append(button);
  row.append(cell);
  return row;
}

function renderFirings(entry, firings) {
  const list = entry.card.querySelector(".firings");
  list.replaceChildren(
    ...firings.slice(-12).reverse().map((f) => {
      const item = document.createElement("li");
      item.className = "firing";
      const when = document.createElement("time");
      when.textContent = new Date(f.t).toLocaleTimeString();
      const sentence = document.createElement("span");
      sentence.className = "sentence";
      sentence.textContent = f.sentence;
      const whyButton = document.createElement("button");
      whyButton.type = "button";
      whyButton.className = "why-link";
      whyButton.textContent = "why?";
      whyButton.addEventListener("click", () => whyFiring(f));
      const raw = document.createElement("details");
      raw.className = "raw";
      const summary = document.createElement("summary");
      summary.textContent = "triples";
      const pre = document.createElement("pre");
      const lines = [
        `rules: ${f.rules.join(", ")}${f.cause_agent ? ` ← ${f.cause_agent}` : ""}`,
        ...f.added.map((t) => `+ ${t.map(short).join(" ")}`),
        ...f.removed.map((t) => `- ${t.map(short).join(" ")}`),
      ];
      pre.textContent = lines.join("\n");
      raw.append(summary, pre);
      item.append(when, " ", sentence, " ", whyButton, raw);
      return item;
    }),
  );
}

function redraw() {
  redrawQueued = false;
  if (!lastState) return;
  for (const robot of lastState.robots) {
    const entry = cardFor(robot.name);
    if (entry.card.hidden) continue;
    const events = history.get(robot.name) || [];
    const [start, end] = windowOf(events);
    const firings = events.filter((e) => e.kind === "firing");
    renderChart(entry, events, start, end, firings);
    renderTimeline(entry, robot, events, start, end, firings);
    renderFirings(entry, firings);
  }
}

// Redraw at most every REDRAW_MS: a charging battery changes the state every tick, and
// a page that re-lays its charts on each change would keep the browser busy.
const REDRAW_MS = 400;
let lastRedraw = 0;

function queueRedraw() {
  if (redrawQueued) return;
  redrawQueued = true;
  const wait = Math.max(0, lastRedraw + REDRAW_MS - performance.now());
  setTimeout(() => requestAnimationFrame(() => {
    lastRedraw = performance.now();
    redraw();
  }), wait);
}

function addHistory(events, reset) {
  if (reset) history.clear();
  for (const event of events) {
    if (event.kind === "reset" || !history.has(event.robot)) history.set(event.robot, []);
    if (event.kind !== "reset") history.get(event.robot).push(event);
  }
  queueRedraw();
}

// A reading written with a lifespan: greyed out once less than a third of it is left (its
// writer missed its renewals: it is about to expire); once the store retracted it, since when
// there has been none and what it last said. `fresh`: see agents/hmi_freshness.py.
function showFreshness(element, fresh, what) {
  delete element.dataset.expires;
  element.classList.remove("expiring", "stale");
  if (!fresh) return;
  if (fresh.stale_since) {
    const since = new Date(fresh.stale_since).toLocaleTimeString();
    element.textContent = `no ${what} since ${since} (last: ${fresh.last})`;
    element.classList.add("stale");
    element.title = `the ${what} expired: its writer stopped renewing it`;
    return;
  }
  element.dataset.expires = fresh.expires;
  element.dataset.life = fresh.life;
  ageFreshness(element);
}

function ageFreshness(element) {
  const left = (Number(element.dataset.expires) - Date.now()) / 1000;
  const expiring = left < Number(element.dataset.life) / 3;
  element.classList.toggle("expiring", expiring);
  element.title = expiring
    ? `about to expire: ${Math.max(0, left).toFixed(1)} s left, not renewed`
    : `expires in ${left.toFixed(0)} s unless written again`;
}

function renderSites(robots) {
  const sites = [...new Set(robots.map((r) => r.site).filter(Boolean))].sort();
  const filter = document.getElementById("site-filter");
  filter.hidden = sites.length < 2;
  const select = document.getElementById("site-select");
  fillSelect(select, [{ name: "", label: "all sites" }, ...sites.map((s) => ({ name: s, label: s }))]);
  for (const robot of robots) {
    cardFor(robot.name).card.hidden = Boolean(select.value) && robot.site !== select.value;
  }
}

function render(state) {
  lastState = state;
  const status = document.getElementById("status");
  status.textContent = state.connected ? "live" : "waiting for the space…";
  status.className = `status ${state.connected ? "online" : "offline"}`;
  document.getElementById("space").textContent = state.space ? `— space ${state.space}` : "";
  for (const robot of state.robots) renderRobot(robot, state);
  renderSites(state.robots);
  renderQuorum(state.cluster || []);
  queueRedraw();
}

// Store replicas on etcd: members each reaches; an embedded store shows nothing.
function renderQuorum(replicas) {
  const line = document.getElementById("quorum");
  line.hidden = replicas.length === 0;
  const told = replicas.map((r) => {
    if (r.silent) return `${r.node}: silent`;
    const reach = `${r.reachable} of ${r.members} members reachable`;
    return r.quorum ? `${r.node}: ${reach}` : `${r.node}: no quorum: ${reach}`;
  });
  line.textContent = `store replicas — ${told.join("; ")}`;
  const whole = replicas.every((r) => r.quorum && !r.silent);
  line.className = `status ${whole ? "online" : "offline"}`;
}

function connect() {
  const events = new EventSource("/events");
  events.addEventListener("history-all", (event) => addHistory(JSON.parse(event.data), true));
  events.addEventListener("history", (event) => addHistory(JSON.parse(event.data), false));
  events.addEventListener("state", (event) => render(JSON.parse(event.data)));
  events.addEventListener("error", () => {
    const status = document.getElementById("status");
    status.textContent = "reconnecting…";
    status.className = "status offline";
  });
}

document.getElementById("why-close").addEventListener("click", () => document.getElementById("why-dialog").close());
document.getElementById("range-select").addEventListener("change", queueRedraw);
document.getElementById("site-select").addEventListener("change", () => lastState && render(lastState));
window.addEventListener("resize", queueRedraw);
setInterval(queueRedraw, 5000); // time moves on: the spans that last until now grow
setInterval(() => document.querySelectorAll("[data-expires]").forEach(ageFreshness), 500);
connect();
