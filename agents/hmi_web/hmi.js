// The HMI page: render the state pushed by /events; send commands to /api/*.
"use strict";

const cards = new Map();

function text(value) {
  return value === null || value === undefined ? "–" : String(value);
}

// options: strings, or {name, label} objects.
function fillSelect(select, options) {
  const pairs = options.map((o) => (typeof o === "string" ? [o, o] : [o.name, o.label]));
  const wanted = JSON.stringify(pairs);
  if (select.dataset.options === wanted) {
    return; // keep the user's choice while the state updates
  }
  select.dataset.options = wanted;
  select.replaceChildren(...pairs.map(([value, label]) => new Option(label, value)));
}

async function send(card, path, body) {
  const feedback = card.querySelector(".feedback");
  feedback.textContent = "sending…";
  try {
    const response = await fetch(path, {
      method: "POST",
      headers: { "Content-Type": "application/json" },
      body: JSON.stringify(body),
    });
    const answer = await response.json();
    feedback.textContent = response.ok ? "done" : `refused: ${answer.error}`;
  } catch (error) {
    feedback.textContent = `failed: ${error}`;
  }
}

function cardFor(name) {
  let card = cards.get(name);
  if (card) {
    return card;
  }
  card = document.getElementById("robot-card").content.firstElementChild.cloneNode(true);
  card.dataset.robot = name;
  card.querySelector(".assign").addEventListener("submit", (event) => {
    event.preventDefault();
    const task = card.querySelector(".task-select").value;
    const request = { robot: name, task, person: card.querySelector(".person-select").value };
    if (task === "Guiding") {
      request.destination = card.querySelector(".place-select").value;
    }
    send(card, "/api/task", request);
  });
  card.querySelector(".battery-form").addEventListener("submit", (event) => {
    event.preventDefault();
    send(card, "/api/battery", { robot: name, level: card.querySelector(".battery-select").value });
  });
  document.getElementById("robots").append(card);
  cards.set(name, card);
  return card;
}

function renderRobot(robot, state) {
  const card = cardFor(robot.name);
  const battery = robot.charge === null ? text(robot.battery) : `${text(robot.battery)} (${robot.charge}%)`;
  const values = { ...robot, battery, task_type: text(robot.task_type) };
  for (const field of card.querySelectorAll("[data-field]")) {
    field.textContent = text(values[field.dataset.field]);
  }
  card.querySelector(".devices tbody").replaceChildren(
    ...robot.devices.map((device) => {
      const row = document.createElement("tr");
      row.dataset.device = device.name;
      for (const [key, value] of [["name", device.name], ["kind", device.kind], ["mode", device.mode]]) {
        const cell = document.createElement("td");
        cell.dataset.field = key;
        cell.textContent = text(value);
        if (key === "mode") {
          cell.className = `mode ${text(value).replace(/\s+/g, "-")}`;
        }
        row.append(cell);
      }
      return row;
    }),
  );
  fillSelect(card.querySelector(".task-select"), state.tasks || []);
  fillSelect(card.querySelector(".person-select"), state.people || []);
  fillSelect(card.querySelector(".place-select"), state.places || []);
  fillSelect(card.querySelector(".battery-select"), state.levels || []);
}

function renderFirings(firings) {
  document.getElementById("firings").replaceChildren(
    ...firings.map((firing) => {
      const item = document.createElement("li");
      item.className = "firing";
      const what = firing.added.length ? firing.added : firing.removed.map((t) => `−${t}`);
      const cause = firing.cause_agent ? ` ← ${firing.cause_agent}: ${firing.cause.join("; ")}` : "";
      const rules = firing.rules.length ? ` [${firing.rules.join(", ")}]` : "";
      item.textContent = `${firing.time} ${firing.agent}${rules}: ${what.join("; ")}${cause}`;
      return item;
    }),
  );
}

function render(state) {
  const status = document.getElementById("status");
  status.textContent = state.connected ? "live" : "waiting for the space…";
  status.className = `status ${state.connected ? "online" : "offline"}`;
  document.getElementById("space").textContent = state.space ? `— space ${state.space}` : "";
  for (const robot of state.robots) {
    renderRobot(robot, state);
  }
  renderFirings(state.firings);
}

function connect() {
  const events = new EventSource("/events");
  events.addEventListener("state", (event) => render(JSON.parse(event.data)));
  events.addEventListener("error", () => {
    const status = document.getElementById("status");
    status.textContent = "reconnecting…";
    status.className = "status offline";
  });
}

connect();
