// enact-hub item page: place library cards into answer slots by drag-and-drop, by click (card
// then slot) or by keyboard (focus a card, press the slot number). Every change is saved to the
// server as a draft, so a reload resumes exactly where the annotator left off.
"use strict";

(function () {
  const root = document.getElementById("annotator");
  if (!root) return;
  const base = root.dataset.base;
  const csrf = document.querySelector('meta[name="csrf-token"]').content;
  const draft = JSON.parse(root.dataset.draft);
  let slots = draft.slots.slice();
  const counts = Object.assign({ placements: 0, swaps: 0, clears: 0, undos: 0 }, draft.counts);
  const history = (draft.history || []).map((h) => h.slice());
  const MAX_HISTORY = 200;

  const slotButtons = Array.from(root.querySelectorAll(".slot"));
  const cards = Array.from(root.querySelectorAll(".card"));
  const cardByLabel = new Map(cards.map((c) => [Number(c.dataset.label), c]));
  const announcer = document.getElementById("announce");
  const submitButton = document.getElementById("submit");
  const undoButton = document.getElementById("undo");
  const saveStatus = document.getElementById("save-status");
  let selected = null;

  const nameOf = (label) => cardByLabel.get(label).dataset.name;
  // The page's messages in its language, from the same catalogue as the page (see
  // SCRIPT_MESSAGES in crates/enact-web/src/i18n.rs); `{name}` marks where a value goes.
  const messages = JSON.parse(root.dataset.messages || "{}");
  const m = (key, values) =>
    (messages[key] || key).replace(/\{(\w+)\}/g, (whole, name) =>
      values && name in values ? String(values[name]) : whole);
  // Why the server refused a draft or an answer, in the page's language when the reply's code
  // is one the page handed over (`refusal-` and the code), else the server's English sentence.
  const refusal = (reply) => {
    const key = "refusal-" + String(reply.code || "").replace(/_/g, "-");
    return key in messages ? m(key, reply.details) : reply.error;
  };
  const announce = (text) => {
    announcer.textContent = text;
  };

  let render = function () {
    slotButtons.forEach((button, i) => {
      const content = button.querySelector(".slot-content");
      content.replaceChildren();
      const label = slots[i];
      button.classList.toggle("filled", label !== null);
      button.draggable = label !== null;
      if (label === null) {
        button.setAttribute("aria-label", m("js-slot-empty", { slot: i + 1 }));
        return;
      }
      const card = cardByLabel.get(label);
      for (const child of card.children) {
        if (child.classList.contains("card-used")) continue;
        content.appendChild(child.cloneNode(true));
      }
      button.setAttribute("aria-label", m("js-slot-filled", { slot: i + 1, name: card.dataset.name }));
    });
    for (const [label, card] of cardByLabel) {
      const at = slots.indexOf(label);
      card.classList.toggle("used", at >= 0);
      card.classList.toggle("selected", selected === label);
      card.setAttribute("aria-pressed", selected === label ? "true" : "false");
      card.querySelector(".card-used").textContent = at >= 0 ? m("js-card-in-slot", { slot: at + 1 }) : "";
    }
    submitButton.disabled = slots.some((s) => s === null);
    undoButton.disabled = history.length === 0;
  }

  let saving = Promise.resolve();
  function save() {
    const body = JSON.stringify({ slots, counts, history });
    saving = saving.then(async () => {
      saveStatus.textContent = m("js-saving");
      try {
        const response = await fetch(`${base}/draft`, {
          method: "POST",
          headers: { "Content-Type": "application/json", "X-CSRF-Token": csrf },
          body,
          credentials: "same-origin",
        });
        if (!response.ok) {
          const error = await response.json().catch(() => ({ error: response.statusText }));
          saveStatus.textContent = m("js-not-saved", { error: refusal(error) });
          return;
        }
        saveStatus.textContent = m("js-saved");
      } catch (e) {
        saveStatus.textContent = m("js-not-saved", { error: e.message });
      }
    });
    return saving;
  }

  function remember() {
    history.push(slots.slice());
    if (history.length > MAX_HISTORY) history.shift();
  }

  function changed(message) {
    selected = null;
    render();
    announce(message);
    save();
  }

  function place(label, index) {
    if (index < 0 || index >= slots.length) return;
    const from = slots.indexOf(label);
    if (from === index) return;
    remember();
    const occupant = slots[index];
    if (from >= 0) slots[from] = occupant;
    slots[index] = label;
    counts.placements += 1;
    let message = m("js-placed", { name: nameOf(label), slot: index + 1 });
    if (occupant !== null) {
      counts.swaps += 1;
      message += from >= 0
        ? " " + m("js-swapped-moved", { name: nameOf(occupant), slot: from + 1 })
        : " " + m("js-swapped-returned", { name: nameOf(occupant) });
    }
    changed(message);
  }

  function clear(index) {
    if (slots[index] === null) return;
    remember();
    const label = slots[index];
    slots[index] = null;
    counts.clears += 1;
    changed(m("js-cleared", { slot: index + 1, name: nameOf(label) }));
  }

  function undo() {
    if (history.length === 0) {
      announce(m("js-nothing-to-undo"));
      return;
    }
    slots = history.pop();
    counts.undos += 1;
    changed(m("js-undone"));
  }

  // Click: a card, then a slot.
  for (const card of cards) {
    const label = Number(card.dataset.label);
    card.addEventListener("click", () => {
      selected = selected === label ? null : label;
      render();
      if (selected !== null) announce(m("js-card-selected", { name: nameOf(label) }));
    });
    card.addEventListener("keydown", (event) => {
      if (event.ctrlKey || event.metaKey || event.altKey) return;
      if (/^[1-9]$/.test(event.key)) {
        event.preventDefault();
        const index = Number(event.key) - 1;
        if (index >= slots.length) {
          announce(m("js-no-such-slot", { key: event.key, count: slots.length }));
          return;
        }
        place(label, index);
        card.focus();
      } else if (event.key === "Backspace" || event.key === "Delete") {
        event.preventDefault();
        const at = slots.indexOf(label);
        if (at >= 0) clear(at);
      }
    });
    card.addEventListener("dragstart", (event) => {
      event.dataTransfer.setData("text/plain", `card:${label}`);
      event.dataTransfer.effectAllowed = "move";
    });
  }

  slotButtons.forEach((button, index) => {
    button.addEventListener("click", () => {
      if (selected !== null) {
        place(selected, index);
      } else if (slots[index] !== null) {
        selected = slots[index];
        render();
        announce(m("js-slot-selected", { name: nameOf(selected) }));
      }
    });
    button.addEventListener("keydown", (event) => {
      if (event.key === "Backspace" || event.key === "Delete") {
        event.preventDefault();
        clear(index);
      }
    });
    button.addEventListener("dragstart", (event) => {
      if (slots[index] === null) return;
      event.dataTransfer.setData("text/plain", `slot:${index}`);
      event.dataTransfer.effectAllowed = "move";
    });
    button.addEventListener("dragover", (event) => {
      event.preventDefault();
      button.classList.add("drop-target");
    });
    button.addEventListener("dragleave", () => button.classList.remove("drop-target"));
    button.addEventListener("drop", (event) => {
      event.preventDefault();
      button.classList.remove("drop-target");
      const [kind, value] = event.dataTransfer.getData("text/plain").split(":");
      if (kind === "card") place(Number(value), index);
      if (kind === "slot" && slots[Number(value)] !== null) place(slots[Number(value)], index);
    });
  });

  // Dropping a placed card back on the library clears its slot.
  const library = root.querySelector(".library");
  library.addEventListener("dragover", (event) => event.preventDefault());
  library.addEventListener("drop", (event) => {
    event.preventDefault();
    const [kind, value] = event.dataTransfer.getData("text/plain").split(":");
    if (kind === "slot") clear(Number(value));
  });

  undoButton.addEventListener("click", undo);
  document.addEventListener("keydown", (event) => {
    const typing = event.target.closest && event.target.closest("textarea, input");
    if (!typing && (event.ctrlKey || event.metaKey) && event.key.toLowerCase() === "z") {
      event.preventDefault();
      undo();
    }
  });

  submitButton.addEventListener("click", async () => {
    if (slots.some((s) => s === null)) return;
    submitButton.disabled = true;
    await saving;
    const response = await fetch(`${base}/submit`, {
      method: "POST",
      headers: { "Content-Type": "application/json", "X-CSRF-Token": csrf },
      body: JSON.stringify({ slots, counts, history }),
      credentials: "same-origin",
    });
    const reply = await response.json().catch(() => ({ error: response.statusText }));
    if (response.ok) {
      announce(m("js-submitted"));
      window.location.assign(reply.next);
    } else {
      saveStatus.textContent = m("js-not-submitted", { error: refusal(reply) });
      submitButton.disabled = false;
    }
  });

  // Lightbox: enlarge any image.
  const lightbox = document.getElementById("lightbox");
  for (const zoom of document.querySelectorAll(".zoom, .zoom-frame")) {
    zoom.addEventListener("click", () => {
      const img = lightbox.querySelector("img");
      img.src = zoom.dataset.src;
      img.alt = zoom.dataset.name;
      lightbox.querySelector(".lightbox-name").textContent = zoom.dataset.name;
      lightbox.showModal();
    });
  }
  lightbox.addEventListener("click", (event) => {
    if (event.target === lightbox) lightbox.close();
  });

  // Inspector: the image (or pair) under the pointer or focus, large, beside the board.
  // Forward: the chosen image and the state before it (the current state, or the image of the
  // slot before). Inverse: the transition's two states.
  const inspector = document.getElementById("inspector");
  const forward = root.classList.contains("forward");
  const current = root.querySelector("figure.current .frame");
  const transitions = Array.from(root.querySelectorAll("li.transition"));
  let inspected = null;

  // `name` is the image's own name (its alt text); `caption` says what it is here.
  function show(figure, src, caption, name) {
    const img = inspector.querySelector(`figure.${figure} img`);
    const text = inspector.querySelector(`figure.${figure} figcaption`);
    if (src) {
      if (img.getAttribute("src") !== src) img.src = src;
      img.alt = name || caption;
      img.hidden = false;
    } else {
      img.hidden = true;
      img.removeAttribute("src");
    }
    text.textContent = caption;
  }

  const srcOf = (label) => (label === null ? null : cardByLabel.get(label).dataset.src);

  // The state before slot `index` (0-based) along the answer as it stands.
  function beforeSlot(index) {
    if (index === 0) {
      const name = current ? current.dataset.name : "";
      return [current && current.dataset.src, m("js-before-start", { name }), name];
    }
    const label = slots[index - 1];
    return label === null
      ? [null, m("js-before-empty", { slot: index }), ""]
      : [srcOf(label), m("js-before-slot", { slot: index, name: nameOf(label) }), nameOf(label)];
  }

  function inspectSlot(index) {
    root.querySelectorAll(".inspected").forEach((e) => e.classList.remove("inspected"));
    if (forward) {
      const [beforeSrc, beforeCaption, beforeName] = beforeSlot(index);
      show("before", beforeSrc, beforeCaption, beforeName);
      const label = slots[index];
      const name = label === null ? "" : nameOf(label);
      show("focus", srcOf(label), label === null ? m("js-focus-slot-empty", { slot: index + 1 }) : m("js-focus-slot", { slot: index + 1, name }), name);
      slotButtons[index].closest("li").classList.add("inspected");
    } else {
      const t = transitions[index];
      const [from, to] = t.querySelectorAll(".frame");
      show("before", from.dataset.src, m("js-transition-before", { index: index + 1, name: from.dataset.name }), from.dataset.name);
      show("focus", to.dataset.src, m("js-transition-after", { index: index + 1, name: to.dataset.name }), to.dataset.name);
      t.classList.add("inspected");
    }
    inspected = { slot: index };
  }

  function inspectCard(label) {
    const at = slots.indexOf(label);
    if (at >= 0) {
      inspectSlot(at);
      return;
    }
    if (forward) {
      root.querySelectorAll(".inspected").forEach((e) => e.classList.remove("inspected"));
      const name = current ? current.dataset.name : "";
      show("before", current && current.dataset.src, m("js-before-start", { name }), name);
      show("focus", srcOf(label), m("js-not-placed", { name: nameOf(label) }), nameOf(label));
      inspected = { card: label };
    }
  }

  for (const card of cards) {
    const label = Number(card.dataset.label);
    card.addEventListener("mouseenter", () => inspectCard(label));
    card.addEventListener("focus", () => inspectCard(label));
  }
  slotButtons.forEach((button, index) => {
    button.addEventListener("mouseenter", () => inspectSlot(index));
    button.addEventListener("focus", () => inspectSlot(index));
  });
  transitions.forEach((t, index) => {
    for (const frame of t.querySelectorAll(".frame")) {
      frame.addEventListener("mouseenter", () => inspectSlot(index));
      frame.addEventListener("focus", () => inspectSlot(index));
    }
  });
  // Placing or clearing changes what a slot shows: refresh the inspector.
  const renderBoard = render;
  render = function () {
    renderBoard();
    if (inspected && inspected.slot !== undefined) inspectSlot(inspected.slot);
    else if (inspected && inspected.card !== undefined) inspectCard(inspected.card);
  };

  // Arrow keys walk the slots, then the cards; the inspector follows focus.
  const walk = slotButtons.concat(cards);
  root.addEventListener("keydown", (event) => {
    if (event.ctrlKey || event.metaKey || event.altKey) return;
    const step = { ArrowDown: 1, ArrowRight: 1, ArrowUp: -1, ArrowLeft: -1 }[event.key];
    if (!step) return;
    const at = walk.indexOf(document.activeElement);
    if (at < 0) return;
    event.preventDefault();
    walk[(at + step + walk.length) % walk.length].focus();
  });

  if (forward) inspectSlot(0);
  else if (transitions.length) inspectSlot(0);
  render();
})();
