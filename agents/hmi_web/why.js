// The HMI page's "why?": ask /api/why and show the reasoner's explanation trees in a dialog.
"use strict";

// Why: ask /api/why for templates ([s, p, o] N-Triples, null for any) and show the trees.
async function why(title, templates) {
  const dialog = document.getElementById("why-dialog");
  const body = document.getElementById("why-body");
  document.getElementById("why-title").textContent = title;
  body.textContent = "asking the reasoner…";
  if (!dialog.open) dialog.showModal();
  const query = templates.map((t) => `t=${encodeURIComponent(JSON.stringify(t))}`).join("&");
  try {
    const response = await fetch(`/api/why?${query}`);
    const answer = await response.json();
    if (!response.ok) {
      body.textContent = `no answer: ${answer.error}`;
    } else if (!answer.explanations.length) {
      body.textContent = "nothing of this holds now (it changed since).";
    } else {
      const list = document.createElement("ul");
      list.className = "why-tree";
      list.append(...answer.explanations.map(whyNode));
      body.replaceChildren(list);
    }
  } catch (error) {
    body.textContent = `failed: ${error}`;
  }
}

function whyNode(node) {
  const item = document.createElement("li");
  item.className = `why-node ${node.holds}`;
  const fact = document.createElement("code");
  fact.textContent = node.text;
  item.append(fact);
  const lines = [];
  if (node.holds === "gone") lines.push("held when the rule fired; replaced since");
  else if (node.repeated) lines.push("(explained above)");
  else if (node.rule) {
    const kind = node.holds === "asserted" ? "production rule" : "rule";
    lines.push(`by ${kind} ${node.rule}${node.where ? ` (${node.where.split("/").slice(-2).join("/")})` : ""}`);
    if (node.comment) lines.push(`“${node.comment}”`);
  }
  if (node.written) {
    const when = node.written.time ? new Date(node.written.time).toLocaleTimeString() : "";
    const seq = node.written.seq ? ` (changeset #${node.written.seq})` : "";
    lines.push(`written by ${node.written.agent}${when ? ` at ${when}` : ""}${seq}`);
  }
  for (const line of lines) {
    const detail = document.createElement("div");
    detail.className = line.startsWith("“") ? "why-comment" : "why-detail";
    detail.textContent = line;
    item.append(detail);
  }
  if (node.premises.length) {
    const list = document.createElement("ul");
    list.append(...node.premises.map(whyNode));
    item.append(list);
  }
  return item;
}


function whyFiring(firing) {
  const templates = firing.added.filter((t) => !t[0].includes("#firing_")).slice(0, 8);
  why(`Why: ${firing.sentence}`, templates);
}
