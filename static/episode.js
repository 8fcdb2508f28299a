// enact-hub episode page: mark key frames on a filmstrip and draw each key frame's scene graph.
// Keyboard first: arrows move between frames, space marks or unmarks the frame shown, and the
// editor is plain form controls (Tab, type, Enter). The mouse works on everything too. Every
// change is described by the server (the transition into the key frame shown, as ENACT's
// sentences and signature components) and kept as a server-side draft, so a reload resumes.
"use strict";

(function () {
  const root = document.getElementById("episode");
  if (!root) return;
  const base = root.dataset.base;
  const csrf = document.querySelector('meta[name="csrf-token"]').content;
  const frames = JSON.parse(root.dataset.frames);
  const graphs = JSON.parse(root.dataset.graphs);
  // key frames by frame position; each { frame, nodes, edges, visible }
  const keyFrames = new Map();
  for (const k of graphs.key_frames || []) {
    keyFrames.set(k.frame, {
      frame: k.frame,
      nodes: k.nodes || [],
      edges: k.edges || [],
      visible: k.visible || null,
    });
  }
  const unaryStates = Array.from(document.getElementById("unary-states").content.children).map(
    (s) => s.textContent);
  const messages = {};
  for (const span of document.getElementById("messages").content.children) {
    messages[span.dataset.key] = span.textContent;
  }
  // The page is in English, as the admin pages are: its script's messages come from the
  // page's own <template id="messages">, not from the translated pages' catalogue
  // (SCRIPT_MESSAGES in crates/enact-web/src/i18n.rs), so each is written once, in the template.
  const say = (key, values) =>
    (messages[key] || key).replace(/\{(\w+)\}/g, (whole, name) =>
      values && name in values ? String(values[name]) : whole);

  const strip = Array.from(document.querySelectorAll(".strip-frame"));
  const large = document.getElementById("large-frame");
  const caption = document.getElementById("frame-caption");
  const keyBadge = document.getElementById("key-badge");
  const keySummary = document.getElementById("key-summary");
  const editorBody = document.getElementById("editor-body");
  const editorEmpty = document.getElementById("editor-empty");
  const nodeRows = document.getElementById("node-rows");
  const edgeRows = document.getElementById("edge-rows");
  const addNode = document.getElementById("add-node");
  const addEdge = document.getElementById("add-edge");
  const problemsBox = document.getElementById("problems");
  const sentencesList = document.getElementById("sentences");
  const signaturesList = document.getElementById("signatures");
  const saveStatus = document.getElementById("save-status");
  const announcer = document.getElementById("announce");
  const announce = (text) => { announcer.textContent = text; };
  const clone = (id) => document.getElementById(id).content.firstElementChild.cloneNode(true);

  let current = keyFrames.size ? Math.min(...keyFrames.keys()) : 0;
  // The server's description of the latest graphs, one entry per transition.
  let described = { transitions: [], problems: [] };

  const sortedKeys = () => Array.from(keyFrames.keys()).sort((a, b) => a - b);
  const document_ = () => ({
    key_frames: sortedKeys().map((f) => {
      const k = keyFrames.get(f);
      const out = { frame: f, nodes: k.nodes, edges: k.edges };
      if (k.visible !== null) out.visible = k.visible;
      return out;
    }),
  });
  // A deep copy (a node's `parent`, if any, comes along).
  const copyGraph = (k) => JSON.parse(JSON.stringify({
    nodes: k.nodes, edges: k.edges, visible: k.visible,
  }));

  // L + 1 key frames make an item of step length L; ENACT asks for L = 3..10.
  const allowedLengths = (count) => {
    const out = [];
    for (let l = 3; l <= 10 && l + 1 <= count; l++) out.push(l);
    return out;
  };

  function toggleKey(position) {
    if (keyFrames.has(position)) {
      keyFrames.delete(position);
      announce(say("unmarked", { n: position, count: keyFrames.size }));
    } else {
      // A new key frame starts as a copy of the key frame before it, so the curator edits
      // only what changed; the first one starts empty.
      const before = sortedKeys().filter((f) => f < position).pop();
      const graph = before === undefined
        ? { nodes: [], edges: [], visible: null }
        : copyGraph(keyFrames.get(before));
      keyFrames.set(position, Object.assign({ frame: position }, graph));
      announce(say("marked", { n: position, count: keyFrames.size }));
    }
    changed();
  }

  // A key frame still empty when first shown takes a copy of the key frame before it: key
  // frames are often marked before any graph is drawn, and the curator should only have to
  // edit what changed.
  function adopt(position) {
    const graph = keyFrames.get(position);
    if (!graph || graph.nodes.length || graph.edges.length) return false;
    const before = sortedKeys().filter((f) => f < position).pop();
    if (before === undefined || !keyFrames.get(before).nodes.length) return false;
    Object.assign(graph, copyGraph(keyFrames.get(before)));
    return true;
  }

  function show(position) {
    current = Math.max(0, Math.min(frames.length - 1, position));
    if (adopt(current)) changed();
    else render();
    const button = strip[current];
    if (button) button.scrollIntoView({ block: "nearest", inline: "nearest" });
  }

  function renderStrip() {
    strip.forEach((button, i) => {
      const isKey = keyFrames.has(i);
      button.classList.toggle("key", isKey);
      button.classList.toggle("current", i === current);
      button.setAttribute("aria-pressed", isKey ? "true" : "false");
      if (i === current) button.setAttribute("aria-current", "true");
      else button.removeAttribute("aria-current");
      button.tabIndex = i === current ? 0 : -1;
    });
    const frame = frames[current];
    if (frame) {
      large.src = frame.src;
      large.alt = say("frame", { n: current, last: frames.length - 1 });
    }
    caption.textContent = say("frame", { n: current, last: frames.length - 1 });
    keyBadge.hidden = !keyFrames.has(current);
    const lengths = allowedLengths(keyFrames.size);
    keySummary.textContent = lengths.length
      ? say("keys", { count: keyFrames.size, lengths: lengths.join(", ") })
      : say("keys-none", { count: keyFrames.size });
  }

  function stateToggle(name, state, checked, onChange) {
    const label = clone("state-template");
    const box = label.querySelector(".state-box");
    box.checked = checked;
    box.dataset.state = state;
    box.setAttribute("aria-label", say("state", { name, state }));
    box.dataset.focus = `state:${name}:${state}`;
    label.querySelector(".state-name").textContent = state;
    box.addEventListener("change", () => onChange(box.checked));
    return label;
  }

  function renderEditor() {
    const graph = keyFrames.get(current);
    editorEmpty.hidden = !!graph;
    editorBody.hidden = !graph;
    nodeRows.replaceChildren();
    edgeRows.replaceChildren();
    if (!graph) return;
    for (const node of graph.nodes) {
      const row = clone("node-row-template");
      row.dataset.name = node.name;
      row.querySelector(".node-name").textContent = node.name;
      row.querySelector(".node-category").textContent = node.category;
      const visible = row.querySelector(".node-visible");
      visible.checked = graph.visible === null || graph.visible.includes(node.name);
      visible.setAttribute("aria-label", say("visible", { name: node.name }));
      visible.dataset.focus = `visible:${node.name}`;
      visible.addEventListener("change", () => {
        const names = graph.visible === null ? graph.nodes.map((n) => n.name) : graph.visible;
        graph.visible = visible.checked
          ? names.concat([node.name])
          : names.filter((n) => n !== node.name);
        // Everyone visible is the default, written as no list at all.
        if (graph.nodes.every((n) => graph.visible.includes(n.name))) graph.visible = null;
        changed();
      });
      const states = row.querySelector(".node-states");
      for (const state of unaryStates) {
        states.appendChild(stateToggle(node.name, state, node.states.includes(state), (on) => {
          node.states = on ? node.states.concat([state]) : node.states.filter((s) => s !== state);
          changed();
        }));
      }
      const remove = row.querySelector(".remove-node");
      remove.setAttribute("aria-label", say("remove-node", { name: node.name }));
      remove.addEventListener("click", () => {
        graph.nodes = graph.nodes.filter((n) => n !== node);
        // Edges to the removed object stay until the curator removes them: the server flags
        // them, which is what a curator who removed the wrong object needs to see.
        if (graph.visible !== null) graph.visible = graph.visible.filter((n) => n !== node.name);
        changed();
      });
      nodeRows.appendChild(row);
    }
    for (const edge of graph.edges) {
      for (const state of edge.states) {
        const row = clone("edge-row-template");
        row.dataset.edge = `${edge.from} ${state} ${edge.to}`;
        row.querySelector(".edge-text").textContent = row.dataset.edge;
        const remove = row.querySelector(".remove-edge");
        remove.setAttribute("aria-label", say("remove-node", { name: row.dataset.edge }));
        remove.addEventListener("click", () => {
          edge.states = edge.states.filter((s) => s !== state);
          if (!edge.states.length) graph.edges = graph.edges.filter((e) => e !== edge);
          changed();
        });
        edgeRows.appendChild(row);
      }
    }
    for (const name of ["from", "to"]) {
      const select = addEdge.elements[name];
      const keep = select.value;
      select.replaceChildren(...graph.nodes.map((n) => new Option(n.name, n.name)));
      if (graph.nodes.some((n) => n.name === keep)) select.value = keep;
    }
  }

  // The transition into the key frame shown, as the server described it.
  function renderTransition() {
    sentencesList.replaceChildren();
    signaturesList.replaceChildren();
    problemsBox.replaceChildren();
    const index = sortedKeys().indexOf(current);
    const problems = (described.problems || []).filter((p) => p.key_frame === index);
    for (const p of problems) {
      const line = document.createElement("p");
      line.className = "notice error";
      line.textContent = p.message;
      problemsBox.appendChild(line);
    }
    if (index < 0) return;
    if (index === 0) {
      const li = document.createElement("li");
      li.className = "meta";
      li.textContent = say("first");
      sentencesList.appendChild(li);
      return;
    }
    const t = (described.transitions || [])[index - 1];
    if (!t) return;
    if (!t.components.length) {
      const line = document.createElement("p");
      line.className = "notice error";
      line.textContent = say("no-change");
      problemsBox.appendChild(line);
    }
    for (const sentence of t.sentences) {
      const li = document.createElement("li");
      li.textContent = sentence;
      sentencesList.appendChild(li);
    }
    for (const component of t.components) {
      const li = document.createElement("li");
      const code = document.createElement("code");
      code.textContent = component;
      li.appendChild(code);
      signaturesList.appendChild(li);
    }
  }

  // Re-rendering replaces the editor's controls: the one that had focus gets it back, so a
  // keyboard user toggling states keeps their place.
  function render() {
    const active = document.activeElement;
    const focusKey = active && active.dataset ? active.dataset.focus : undefined;
    renderStrip();
    renderEditor();
    renderTransition();
    if (focusKey) {
      const again = Array.from(root.querySelectorAll("[data-focus]"))
        .find((el) => el.dataset.focus === focusKey);
      if (again) again.focus();
    }
  }

  async function post(path, body) {
    const response = await fetch(base + path, {
      method: "POST",
      headers: { "Content-Type": "application/json", "X-CSRF-Token": csrf, Accept: "application/json" },
      body: JSON.stringify(body),
    });
    const data = await response.json().catch(() => ({}));
    if (!response.ok) throw new Error(data.error || data.message || response.statusText);
    return data;
  }

  // Describing and keeping the draft run after the curator pauses; the latest change wins.
  let pending = null;
  let generation = 0;
  function changed() {
    render();
    // Until the server has described this change, nothing on screen claims it is saved.
    saveStatus.textContent = "";
    clearTimeout(pending);
    const mine = ++generation;
    pending = setTimeout(async () => {
      const doc = document_();
      try {
        const [description] = await Promise.all([
          post("/describe", doc),
          post("/draft", doc),
        ]);
        if (mine !== generation) return;
        described = description;
        saveStatus.textContent = say("draft");
        renderTransition();
      } catch (e) {
        if (mine === generation) saveStatus.textContent = say("failed", { error: e.message });
      }
    }, 250);
  }

  addNode.addEventListener("submit", (event) => {
    event.preventDefault();
    const graph = keyFrames.get(current);
    if (!graph) return;
    const name = addNode.elements.name.value.trim();
    const category = addNode.elements.category.value.trim();
    if (graph.nodes.some((n) => n.name === name)) {
      announce(say("name-taken", { name }));
      saveStatus.textContent = say("name-taken", { name });
      return;
    }
    graph.nodes.push({ name, category, states: [] });
    if (graph.visible !== null) graph.visible.push(name);
    addNode.reset();
    changed();
    addNode.elements.name.focus();
  });

  addEdge.addEventListener("submit", (event) => {
    event.preventDefault();
    const graph = keyFrames.get(current);
    if (!graph) return;
    const from = addEdge.elements.from.value;
    const to = addEdge.elements.to.value;
    const state = addEdge.elements.state.value;
    let edge = graph.edges.find((e) => e.from === from && e.to === to);
    if (edge && edge.states.includes(state)) {
      saveStatus.textContent = say("edge-exists");
      return;
    }
    if (!edge) {
      edge = { from, to, states: [] };
      graph.edges.push(edge);
    }
    edge.states.push(state);
    changed();
  });

  document.getElementById("save").addEventListener("click", async () => {
    clearTimeout(pending);
    generation++;
    try {
      described = await post("/graphs", document_());
      saveStatus.textContent = say("saved");
      announce(say("saved"));
    } catch (e) {
      saveStatus.textContent = say("failed", { error: e.message });
      announce(saveStatus.textContent);
    }
    renderTransition();
  });

  document.getElementById("toggle-key").addEventListener("click", () => toggleKey(current));
  strip.forEach((button, i) => {
    button.addEventListener("click", () => show(i));
    button.addEventListener("dblclick", () => toggleKey(i));
  });

  // Frame keys work anywhere on the page except inside a form control, where they type.
  document.addEventListener("keydown", (event) => {
    const t = event.target;
    if (t.closest && t.closest("input, select, textarea, button:not(.strip-frame)")) return;
    if (event.altKey || event.ctrlKey || event.metaKey) return;
    const keys = sortedKeys();
    let to = null;
    if (event.key === "ArrowRight") to = current + 1;
    else if (event.key === "ArrowLeft") to = current - 1;
    else if (event.key === "Home") to = 0;
    else if (event.key === "End") to = frames.length - 1;
    else if (event.key === "PageDown") to = keys.find((f) => f > current);
    else if (event.key === "PageUp") to = keys.filter((f) => f < current).pop();
    else if (event.key === " ") {
      event.preventDefault();
      toggleKey(current);
      return;
    } else return;
    event.preventDefault();
    if (to === undefined) return;
    show(to);
    if (strip[current]) strip[current].focus();
  });

  render();
  if (keyFrames.size) changed();
})();
