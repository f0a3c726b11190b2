//! A benchmark's `index.html`.

use crate::results::BenchResult;
use isotrack_html::{escape, page, script_json};

/// The page of a benchmark's results: the sortable leaderboard, then per task its picture (each
/// controller's path on the first scoring seed over the field, the target isoline dashed) and
/// its table (mean score and score parts, outcomes, the gains the built-in laws ran with).
pub fn benchmark_page(r: &BenchResult) -> String {
    let title = format!("isotrack benchmark: {} v{}", r.suite, r.version);
    let body = format!(
        r#"<h1>{t}</h1>
<p class="sub">{n} controllers on {m} tasks. Score per run in [0, 100] (formula {v}): {f}, 0 for a run that leaves the field or diverges; a task's score is the mean over its scoring seeds, the overall score the mean over tasks. Click a column to sort.</p>{team}
<h2>Leaderboard</h2>
<table id="leaderboard"></table>
<div id="tasks"></div>
<p class="note" id="status">loading</p>"#,
        t = escape(&title),
        n = r.controllers.len(),
        m = r.tasks.len(),
        v = i64::from(r.scoring),
        f = escape(r.scoring.formula()),
        team = if r.tasks.iter().any(|t| t.team) {
            format!(
                "\n<p class=\"sub\">{}</p>",
                escape(crate::score::TEAM_FORMULA)
            )
        } else {
            String::new()
        },
    );
    page(&title, &body, &script_json(r), BENCH_JS)
}

const BENCH_JS: &str = r##"
(function () {
  const R = ISO, ctrls = R.controllers;
  const colourOf = {}; ctrls.forEach((c, i) => colourOf[c] = colour(i));
  // Leaderboard: one row per controller, overall then one column per task.
  const rows = R.overall.map(([c, overall], rank) => {
    const row = { controller: c, rank: rank + 1, overall: overall };
    for (const t of R.tasks) { const s = t.scores.find(x => x[0] === c); row[t.id] = s ? s[1] : 0; }
    return row;
  });
  const cols = ["rank", "controller", "overall"].concat(R.tasks.map(t => t.id));
  const table = document.getElementById("leaderboard");
  let sortCol = "overall", desc = true;
  function render() {
    table.innerHTML = "";
    const head = el("tr");
    for (const c of cols) {
      const th = el("th", { "data-col": c }, c);
      if (c === sortCol) th.className = desc ? "sorted-desc" : "sorted-asc";
      th.addEventListener("click", () => {
        if (sortCol === c) desc = !desc; else { sortCol = c; desc = c !== "rank" && c !== "controller"; }
        render();
      });
      head.appendChild(th);
    }
    table.appendChild(head);
    const sorted = rows.slice().sort((a, b) => {
      const x = a[sortCol], y = b[sortCol];
      const d = typeof x === "string" ? x.localeCompare(y) : x - y;
      return desc ? -d : d;
    });
    for (const r of sorted) {
      const tr = el("tr", { "data-controller": r.controller });
      for (const c of cols) {
        const v = r[c];
        const td = el("td", {}, typeof v === "number" && c !== "rank" ? v.toFixed(1) : String(v));
        if (c === "controller") {
          const sw = el("span", { class: "swatch" }); sw.style.background = colourOf[r.controller];
          td.prepend(sw);
        }
        tr.appendChild(td);
      }
      table.appendChild(tr);
    }
  }
  render();
  // Per task: the picture and the table.
  const tasks = document.getElementById("tasks");
  const partNames = ["capture", "band", "distance", "losses", "effort"];
  for (const t of R.tasks) {
    const sec = el("section", { id: "task-" + t.id, "data-task": t.id });
    sec.appendChild(el("h2", {}, t.id + ": " + t.title));
    const box = el("div", { class: "task" });
    const fig = el("div");
    const canvas = el("canvas", { width: 340, height: 340, "aria-label": "paths over the field, task " + t.id });
    fig.appendChild(canvas);
    const legend = el("div", { class: "legend" });
    const toPx = drawField(canvas, t.picture);
    const ctx = canvas.getContext("2d");
    for (const tr of t.trajectories) {
      drawPath(ctx, toPx, tr.points.map(p => p[0]), tr.points.map(p => p[1]), colourOf[tr.controller], 1.6);
      if (tr.points.length > 0) {
        const p = toPx(tr.points[0][0], tr.points[0][1]);
        ctx.fillStyle = "#000"; ctx.beginPath(); ctx.arc(p[0], p[1], 3, 0, 2 * Math.PI); ctx.fill();
      }
      const item = el("span", {}, tr.controller + (tr.outcome === "completed" ? "" : " (" + tr.outcome + ")"));
      const sw = el("span", { class: "swatch" }); sw.style.background = colourOf[tr.controller];
      item.prepend(sw); legend.appendChild(item);
    }
    fig.appendChild(legend);
    fig.appendChild(el("p", { class: "note" }, "isoline s_d = " + fmt(t.picture.level) + " dashed; field at t = 0; first scoring seed; dot: start"));
    box.appendChild(fig);
    const tab = el("table");
    const head = el("tr");
    for (const h of ["controller", "score"].concat(partNames).concat(["outcomes", "gains"])) head.appendChild(el("th", {}, h));
    tab.appendChild(head);
    for (const [c, s] of t.scores) {
      const runs = t.runs.filter(r => r.controller === c);
      const tr = el("tr", { "data-controller": c });
      tr.appendChild(el("td", {}, c));
      tr.appendChild(el("td", {}, s.toFixed(1)));
      for (let k = 0; k < 5; k++) {
        const m = runs.reduce((a, r) => a + r.score.parts[k], 0) / Math.max(1, runs.length);
        tr.appendChild(el("td", {}, m.toFixed(2)));
      }
      const counts = {};
      for (const r of runs) counts[r.outcome] = (counts[r.outcome] || 0) + 1;
      tr.appendChild(el("td", {}, Object.entries(counts).map(([k, v]) => v + " " + k).join(", ")));
      const g = t.gains[c];
      tr.appendChild(el("td", {}, g ? Object.entries(g).map(([k, v]) => k + "=" + fmt(v, 3)).join(" ") : "(own)"));
      tab.appendChild(tr);
    }
    box.appendChild(tab);
    sec.appendChild(box);
    tasks.appendChild(sec);
  }
  const status = document.getElementById("status");
  status.textContent = "ready: " + ctrls.length + " controllers, " + R.tasks.length + " tasks";
  document.body.setAttribute("data-ready", "1");
})();
"##;
