/* gaitpref operator console: keyboard shortcuts, the confirm step, no double posts.
   Plain JavaScript, no build step. Without it the pages still work (the server asks to confirm). */
"use strict";
(function () {
  const dialog = document.getElementById("confirm-dialog");
  let pendingForm = null;

  function typing(target) {
    if (!target || !target.tagName) return false;
    const tag = target.tagName;
    if (tag === "TEXTAREA" || tag === "SELECT") return true;
    return tag === "INPUT" && !["radio", "checkbox", "button", "submit", "hidden"].includes(target.type);
  }

  // a control of a form other than ``form`` (the validation page's withdraw form: its "also
  // undo" checkbox, its button): Enter there is that form's, never ``form``'s shortcut
  function ofAnotherForm(target, form) {
    const own = target && target.closest ? target.closest("form") : null;
    return own !== null && own !== form;
  }

  function lock(form) {
    for (const b of document.querySelectorAll("button")) b.disabled = true;
    form.setAttribute("aria-busy", "true");
  }

  function summaryOf(form) {
    const kind = form.dataset.confirm;
    const lines = [];
    if (kind === "answer") {
      for (const input of form.querySelectorAll("input[type=radio]:checked")) {
        if (input.dataset.say) lines.push(input.dataset.say);
      }
      if (!form.querySelector("fieldset[data-kind=suggestion] input:checked[value]:not([value=''])")) {
        lines.push("No suggestions");
      }
      const note = form.querySelector("textarea[name=note]");
      if (note && note.value.trim()) lines.push("Note: " + note.value.trim());
    } else if (kind === "ranking") {
      const picks = ["rank1", "rank2", "rank3"].map((n) => form.elements[n].value);
      lines.push("Best " + picks[0] + ", then " + picks[1] + ", worst " + picks[2]);
    } else {
      const button = form.querySelector("button[data-say]");
      if (button) lines.push(button.dataset.say);
      const reason = form.elements.namedItem("reason");
      if (kind === "unsafe" && reason) lines.push("Reason: " + reason.value.trim());
      if (kind === "exclude" && reason) {
        const detail = form.elements.namedItem("detail");
        const more = detail && detail.value.trim() ? " (" + detail.value.trim() + ")" : "";
        lines.push("Reason: " + reason.value.replace(/_/g, " ") + more);
      }
    }
    return lines;
  }

  const TITLES = { answer: "Save this answer?", undo: "Undo the last answer?",
    ranking: "Record this ranking?", finish: "Finish the session?",
    unsafe: "Flag this trial unsafe?", withdraw: "Withdraw the unsafe flag?",
    exclude: "Exclude this trial?" };

  function ask(form) {
    if (!dialog) { confirmAndSend(form); return; }
    pendingForm = form;
    const title = dialog.querySelector("[data-title]");
    if (title) title.textContent = TITLES[form.dataset.confirm] || "Confirm?";
    const list = dialog.querySelector("ul");
    list.textContent = "";
    for (const line of summaryOf(form)) {
      const li = document.createElement("li");
      li.textContent = line;
      list.appendChild(li);
    }
    dialog.showModal();
    dialog.querySelector("[data-confirm-yes]").focus();
  }

  function confirmAndSend(form) {
    const flag = form.elements.namedItem("confirmed");
    if (flag) flag.value = "1";
    form.dataset.confirmed = "1";
    if (dialog && dialog.open) dialog.close();
    form.requestSubmit();
  }

  if (dialog) {
    dialog.querySelector("[data-confirm-yes]").addEventListener("click", () => {
      if (pendingForm) confirmAndSend(pendingForm);
    });
    dialog.querySelector("[data-confirm-no]").addEventListener("click", () => dialog.close());
    dialog.addEventListener("close", () => { if (pendingForm && pendingForm.dataset.confirmed !== "1") pendingForm = null; });
  }

  // every form: one post only; forms with data-confirm go through the confirm step first
  for (const form of document.querySelectorAll("form")) {
    form.addEventListener("submit", (event) => {
      if (form.dataset.sent === "1") { event.preventDefault(); return; }
      if (form.dataset.confirm && form.dataset.confirmed !== "1") {
        event.preventDefault();
        if (!ready(form)) return;
        ask(form);
        return;
      }
      form.dataset.sent = "1";
      setTimeout(() => lock(form), 0);
    });
  }

  // "Flag trial N unsafe" or "exclude" opened: the focus goes to its reason, to be typed at once
  for (const details of document.querySelectorAll("details.unsafe, details.exclude")) {
    details.addEventListener("toggle", () => {
      const field = details.querySelector("[name=reason]");
      if (details.open && field) field.focus();
    });
  }

  // -- the answer form -----------------------------------------------------------------------
  const answer = document.getElementById("answer-form");
  const cmpGroups = answer ? [...answer.querySelectorAll("fieldset[data-kind=comparison]")] : [];
  const sugGroups = answer ? [...answer.querySelectorAll("fieldset[data-kind=suggestion]")] : [];
  const ratGroups = answer ? [...answer.querySelectorAll("fieldset[data-kind=rating]")] : [];
  const positions = [...new Set(sugGroups.map((g) => Number(g.dataset.position)))];
  let activeCmp = 0;
  let activeRat = 0;
  let activePos = positions.length ? positions[0] : 0;
  const answered = (g) => !!g.querySelector("input:checked");
  const rated = (g) => !!g.querySelector("input:checked:not([value=''])");
  // ratings take the digits once every comparison is answered (the comparison comes first)
  const digitsRate = () => ratGroups.length > 0 && cmpGroups.every(answered);

  function mark() {
    cmpGroups.forEach((g, i) => g.classList.toggle("active", i === activeCmp));
    sugGroups.forEach((g) => g.classList.toggle("active", Number(g.dataset.position) === activePos));
    ratGroups.forEach((g, i) => g.classList.toggle("active", i === activeRat));
  }

  function ready(form) {
    if (form !== answer) return true;
    const missing = cmpGroups.filter((g) => !answered(g));
    cmpGroups.forEach((g) => {
      g.classList.toggle("missing", missing.includes(g));
      if (missing.includes(g)) g.setAttribute("aria-invalid", "true"); else g.removeAttribute("aria-invalid");
    });
    const hint = document.getElementById("hint");
    if (missing.length) {
      activeCmp = cmpGroups.indexOf(missing[0]);
      mark();
      if (hint) { hint.hidden = false; hint.textContent = "Answer the comparison first (1, 2 or 0)."; }
      missing[0].scrollIntoView({ block: "center" });
      return false;
    }
    if (hint) hint.hidden = true;
    return true;
  }

  if (answer) {
    answer.addEventListener("change", (event) => {
      const group = event.target.closest("fieldset");
      if (!group) return;
      if (group.dataset.kind === "comparison") {
        group.classList.remove("missing");
        group.removeAttribute("aria-invalid");
        activeCmp = cmpGroups.indexOf(group);
        const next = cmpGroups.findIndex((g) => !answered(g));
        if (next >= 0) activeCmp = next;
      } else if (group.dataset.kind === "rating") {
        activeRat = ratGroups.indexOf(group);
        if (rated(group)) {
          const next = ratGroups.findIndex((g, i) => i > activeRat && !rated(g));
          if (next >= 0) activeRat = next;
        }
      } else {
        activePos = Number(group.dataset.position);
      }
      mark();
    });
  }

  function choose(key) {
    const scopes = [];
    if (digitsRate()) { if (ratGroups[activeRat]) scopes.push(ratGroups[activeRat]); }
    else if (cmpGroups[activeCmp]) scopes.push(cmpGroups[activeCmp]);
    for (const g of sugGroups) if (Number(g.dataset.position) === activePos) scopes.push(g);
    for (const scope of scopes) {
      const input = scope.querySelector('input[data-key="' + CSS.escape(key) + '"]');
      if (input) {
        input.checked = true;
        input.dispatchEvent(new Event("change", { bubbles: true }));
        return true;
      }
    }
    return false;
  }

  // -- the ranking form ----------------------------------------------------------------------
  const ranking = document.getElementById("ranking-form");
  function pick(label) {
    const selects = ["rank1", "rank2", "rank3"].map((n) => ranking.elements[n]);
    if (selects.some((s) => s.value === label)) return;
    const free = selects.find((s) => !s.value);
    if (free) free.value = label;
  }
  function unpick() {
    const selects = ["rank1", "rank2", "rank3"].map((n) => ranking.elements[n]).reverse();
    const last = selects.find((s) => s.value);
    if (last) last.value = "";
  }
  function showPicks() {
    const chosen = ["rank1", "rank2", "rank3"].map((n) => ranking.elements[n].value);
    for (const b of ranking.querySelectorAll("[data-pick]")) {
      b.setAttribute("aria-pressed", chosen.includes(b.dataset.pick) ? "true" : "false");
    }
  }
  if (ranking) {
    for (const b of ranking.querySelectorAll("[data-pick]")) b.addEventListener("click", () => { pick(b.dataset.pick); showPicks(); });
    const clear = ranking.querySelector("[data-pick-clear]");
    if (clear) clear.addEventListener("click", () => { ["rank1", "rank2", "rank3"].forEach((n) => { ranking.elements[n].value = ""; }); showPicks(); });
    ranking.addEventListener("change", showPicks);
  }

  // -- keyboard ------------------------------------------------------------------------------
  // a control outside the answer and ranking forms that Enter activates itself (Tab, then Enter
  // on "Flag trial 3 unsafe", "Pause", a link); inside those forms Enter reviews the form
  const activates = (target) => !!(target && target.closest
    && target.closest("button, a[href], summary") && !target.closest("#answer-form, #ranking-form"));

  // N (its data-key): "Flag trial N unsafe" opened, the focus in its reason; the flag still
  // takes the reason, Enter (its review) and Enter (confirm). The key's own repeats, until it
  // is released, are swallowed: a held N types nothing into the reason
  const flagLast = document.getElementById("unsafe-last");
  let flagHeld = null;
  function openFlag() {
    flagLast.open = true;
    const field = flagLast.querySelector("[name=reason]");
    if (field) field.focus();
  }
  document.addEventListener("keyup", (event) => { if (event.code === flagHeld) flagHeld = null; });

  // a freshly loaded page takes no shortcut until the keys have rested GUARD_MS: Enters pressed
  // quickly on after a confirm land on the next page when it loads among them, and there (a
  // query that asks no comparison may be saved empty) they would review and confirm a trial
  // never walked. Until then Enter, Backspace and the letter and digit keys outside a text field
  // do nothing (not even the browser's Enter on a focused button) and each such press starts
  // the wait again; an open review is not confirmed; text fields type as ever. The page says
  // when its keys are live: <html data-keys="ready">
  const GUARD_MS = 500;
  let settled = false;
  let guard = 0;
  function rest() {
    clearTimeout(guard);
    guard = setTimeout(() => { settled = true; document.documentElement.dataset.keys = "ready"; }, GUARD_MS);
  }
  rest();

  document.addEventListener("keydown", (event) => {
    if (flagHeld !== null && event.code === flagHeld && event.repeat) { event.preventDefault(); return; }
    if (event.ctrlKey || event.metaKey || event.altKey) return;
    if (!settled && (event.key === "Enter" || event.key === "Backspace" || event.key.length === 1)
        && ((dialog && dialog.open) || !typing(event.target))) {
      event.preventDefault();
      rest();
      return;
    }
    if (dialog && dialog.open) {
      const onBack = document.activeElement && document.activeElement.hasAttribute("data-confirm-no");
      // a held Enter repeats: the repeats never confirm (nor click the focused Confirm)
      if (event.key === "Enter" && event.repeat) { event.preventDefault(); return; }
      if (event.key === "Enter" && !onBack) {
        event.preventDefault();
        if (pendingForm) confirmAndSend(pendingForm);
      }
      return; // Esc closes the dialog natively; Enter on "Back" goes back
    }
    if (typing(event.target)) {
      if (event.key === "Escape") event.target.blur();
      return;
    }
    const key = event.key.length === 1 ? event.key.toLowerCase() : event.key;
    // a held key acts once: its repeats choose, review, undo or rank nothing more
    if (event.repeat && (key.length === 1 || key === "Enter" || key === "Backspace")) {
      event.preventDefault();
      return;
    }
    if (key === "Enter" && activates(event.target)) return;
    if (flagLast && flagLast.dataset.key && key === flagLast.dataset.key) {
      event.preventDefault();
      flagHeld = event.code;
      openFlag();
      return;
    }
    if (answer) {
      if (key === "Enter") { event.preventDefault(); answer.requestSubmit(); return; }
      if (key === "m") { event.preventDefault(); document.getElementById("note").focus(); return; }
      if ((key === "." || key === ",") && positions.length > 1) {
        const k = positions.indexOf(activePos) + (key === "." ? 1 : -1);
        activePos = positions[(k + positions.length) % positions.length];
        mark();
        event.preventDefault();
        return;
      }
      if (choose(key)) { event.preventDefault(); return; }
    }
    if (key === "u") {
      const undo = document.getElementById("undo-form");
      if (undo) { event.preventDefault(); undo.requestSubmit(); return; }
    }
    if (ranking) {
      if (["a", "b", "c"].includes(key)) { pick(key.toUpperCase()); showPicks(); event.preventDefault(); return; }
      if (key === "Backspace") { unpick(); showPicks(); event.preventDefault(); return; }
      if (key === "Enter") {
        if (ofAnotherForm(event.target, ranking)) return; // the browser's: a button is pressed
        event.preventDefault();
        ranking.requestSubmit();
        return;
      }
    }
  });
  mark();
  // a page restored from the back/forward cache may show a form already sent: load it afresh
  window.addEventListener("pageshow", (event) => { if (event.persisted) window.location.reload(); });
})();
