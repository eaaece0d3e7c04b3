// The HMI page's history of a robot: battery and speed plotted with uPlot (vendor/), and a
// timeline of tasks and device modes laid out with plain elements, firings marked on both.
"use strict";

function windowOf(events) {
  const now = Date.now() / 1000;
  const range = Number(document.getElementById("range-select").value);
  const first = events.length ? events[0].t / 1000 : now - 60;
  const start = range ? Math.max(first, now - range) : first;
  return [Math.min(start, now - 10), now];
}

// Battery (%) and speed as series over one x array, each value held until the next.
function series(events, start, end) {
  const xs = [];
  const charge = [];
  const speed = [];
  let c = null;
  let s = null;
  for (const e of events) {
    if (e.kind === "battery" && e.charge !== undefined) c = e.charge;
    else if (e.kind === "speed") s = SPEEDS[e.value] ?? null;
    else continue;
    const t = e.t / 1000;
    if (t < start) continue;
    if (!xs.length && t > start) {
      xs.push(start);
      charge.push(null);
      speed.push(null);
    }
    xs.push(t);
    charge.push(c);
    speed.push(s);
  }
  if (!xs.length) {
    xs.push(start);
    charge.push(c);
    speed.push(s);
  }
  xs.push(end);
  charge.push(c);
  speed.push(s);
  return [xs, charge, speed];
}

function firingMarks(firings) {
  return (u) => {
    const ctx = u.ctx;
    ctx.save();
    ctx.strokeStyle = "rgba(130, 60, 200, 0.55)";
    ctx.lineWidth = Math.max(1, devicePixelRatio);
    for (const f of firings) {
      const x = u.valToPos(f.t / 1000, "x", true);
      if (x < u.bbox.left || x > u.bbox.left + u.bbox.width) continue;
      ctx.beginPath();
      ctx.moveTo(x, u.bbox.top);
      ctx.lineTo(x, u.bbox.top + u.bbox.height);
      ctx.stroke();
    }
    ctx.restore();
  };
}

function renderChart(entry, events, start, end, firings) {
  const holder = entry.card.querySelector(".chart");
  const width = Math.max(300, holder.clientWidth);
  const data = series(events, start, end);
  if (entry.chart && entry.chart.width !== width) {
    entry.chart.destroy();
    entry.chart = null;
  }
  entry.firings = firings;
  if (!entry.chart) {
    const speedNames = Object.keys(SPEEDS);
    entry.chart = new uPlot(
      {
        width,
        height: 190,
        scales: { x: { time: true }, "%": { range: [0, 100] }, speed: { range: [-0.2, 3.2] } },
        axes: [
          {},
          { scale: "%", label: "battery %", size: 50 },
          {
            scale: "speed",
            side: 1,
            label: "speed",
            size: 60,
            splits: () => [0, 1, 2, 3],
            values: (u, splits) => splits.map((v) => speedNames[v] ?? ""),
            grid: { show: false },
          },
        ],
        series: [
          {},
          { label: "battery %", scale: "%", stroke: "#1f6feb", width: 2, fill: "rgba(31,111,235,0.08)", paths: uPlot.paths.stepped({ align: 1 }) },
          { label: "speed", scale: "speed", stroke: "#d4760a", width: 2, paths: uPlot.paths.stepped({ align: 1 }) },
        ],
        hooks: { draw: [(u) => firingMarks(entry.firings)(u), () => align(entry)] },
        legend: { live: false },
      },
      data,
      holder,
    );
    window.__charts.set(entry.card.dataset.robot, entry.chart);
  } else {
    entry.chart.setData(data);
  }
}

function lane(label, spans, start, end, kind) {
  const row = document.createElement("div");
  row.className = `lane ${kind}`;
  const name = document.createElement("span");
  name.className = "lane-name";
  name.textContent = label;
  const track = document.createElement("div");
  track.className = "track";
  for (const [from, to, value] of spans) {
    const a = Math.max(from, start);
    const b = Math.min(to, end);
    if (b <= a) continue;
    const span = document.createElement("span");
    span.className = `span ${slug(value)}`;
    span.style.left = `${((a - start) / (end - start)) * 100}%`;
    span.style.width = `${((b - a) / (end - start)) * 100}%`;
    span.textContent = value;
    span.title = `${value} from ${new Date(from * 1000).toLocaleTimeString()}`;
    track.append(span);
  }
  row.append(name, track);
  return row;
}

// Spans of one value over time: [from, to, value], each until the next change.
function spans(events, pick, end) {
  const out = [];
  for (const e of events) {
    const value = pick(e);
    if (value === undefined) continue;
    if (out.length) out[out.length - 1][1] = e.t / 1000;
    out.push([e.t / 1000, end, value]);
  }
  return out;
}

function renderTimeline(entry, robot, events, start, end, firings) {
  const timeline = entry.card.querySelector(".timeline");
  const lanes = [lane("task", spans(events, (e) => (e.kind === "task" ? e.value : undefined), end), start, end, "task")];
  for (const device of robot.devices) {
    if (!device.mode) continue;
    const picked = spans(events, (e) => (e.kind === "mode" && e.device === device.name && e.commanded ? e.commanded : undefined), end);
    if (!picked.length) continue;
    const shown = device.name.startsWith(`${robot.name}_`) ? device.name.slice(robot.name.length + 1) : device.name;
    lanes.push(lane(shown, picked, start, end, "mode"));
  }
  const marks = document.createElement("div");
  marks.className = "lane firings-lane";
  const name = document.createElement("span");
  name.className = "lane-name";
  name.textContent = "firings";
  const track = document.createElement("div");
  track.className = "track";
  for (const f of firings) {
    const t = f.t / 1000;
    if (t < start) continue;
    const mark = document.createElement("button");
    mark.type = "button";
    mark.className = "mark";
    mark.style.left = `${((t - start) / (end - start)) * 100}%`;
    mark.title = f.sentence;
    mark.setAttribute("aria-label", `why: ${f.sentence}`);
    mark.addEventListener("click", () => whyFiring(f));
    track.append(mark);
  }
  marks.append(name, track);
  lanes.push(marks);
  timeline.replaceChildren(...lanes);
  align(entry);
}

// Lay the timeline's tracks under the chart's plot area (known once uPlot has drawn).
function align(entry) {
  const over = entry.chart?.over;
  if (!over || !over.offsetWidth) return;
  const timeline = entry.card.querySelector(".timeline");
  timeline.style.setProperty("--plot-left", `${over.offsetLeft}px`);
  timeline.style.setProperty("--plot-width", `${over.offsetWidth}px`);
}
