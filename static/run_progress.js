// enact-hub run page: keeps a model run's progress live without reloading. The page is
// complete as served; this only polls the run's JSON view every two seconds, rewrites the
// figures, and shows the pause/resume/cancel buttons that apply to the job's state. Polling
// stops once the job has ended.
"use strict";

(function () {
  const root = document.getElementById("run-progress");
  if (!root) return;
  const url = root.dataset.progressUrl;
  const field = (name) => document.querySelector('[data-field="' + name + '"]');
  const controls = Array.from(document.querySelectorAll("form[data-when]"));
  const ENDED = ["done", "failed", "cancelled"];
  const EVERY_MS = 2000;

  const count = (p, name) => (typeof p[name] === "number" ? p[name] : 0);
  const duration = (seconds) => {
    const s = Math.max(0, Math.round(seconds));
    const h = Math.floor(s / 3600);
    const m = Math.floor((s % 3600) / 60);
    const pad = (n) => String(n).padStart(2, "0");
    if (h > 0) return h + " h " + pad(m) + " min";
    if (m > 0) return m + " min " + pad(s % 60) + " s";
    return s + " s";
  };
  const set = (name, text) => {
    const el = field(name);
    if (el && el.textContent !== text) el.textContent = text;
  };

  const show = (run) => {
    const p = run.progress || {};
    const state = run.state;
    set("stage", state ? (p.stage && p.stage !== state ? state + " (" + p.stage + ")" : state) : "not started on the server");
    set("done", count(p, "done") + " of " + count(p, "total"));
    set("answered", String(count(p, "answered")));
    set("failed", String(count(p, "failed")));
    set("in_flight", String(count(p, "in_flight")));
    set("items_per_s", count(p, "items_per_s").toFixed(2));
    set("eta", typeof p.eta_s === "number" ? duration(p.eta_s) : "–");
    set("tokens", count(p, "prompt_tokens") + " in, " + count(p, "completion_tokens") + " out");
    set("cost", "$" + count(p, "cost_usd").toFixed(4));
    const list = field("recent_errors");
    if (list) {
      const errors = Array.isArray(p.recent_errors) ? p.recent_errors : [];
      list.replaceChildren(
        ...errors.map((e) => {
          const li = document.createElement("li");
          li.textContent = e;
          return li;
        })
      );
    }
    for (const form of controls) {
      form.hidden = !(state && form.dataset.when.split(" ").includes(state));
    }
    return !ENDED.includes(state);
  };

  const poll = async () => {
    let again = true;
    try {
      const response = await fetch(url, { credentials: "same-origin", headers: { Accept: "application/json" } });
      if (response.ok) again = show(await response.json());
    } catch (_) {
      // A failed poll (server restarting) is tried again at the next tick.
    }
    if (again) setTimeout(poll, EVERY_MS);
  };
  setTimeout(poll, EVERY_MS);
})();
