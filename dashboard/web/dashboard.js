// The dashboard page: polls /api/state (dashboard/src/state.cpp says what is in it) and
// draws it with Chart.js and its matrix plugin.
'use strict';

const POLL_MS = 500;
const charts = {};
let shownVersion = -1;
let shownFrame = '';

function $(id) { return document.getElementById(id); }
function filled(panel) { $(panel).dataset.state = 'filled'; }
function fmt(x, digits = 3) { return x === null || x === undefined ? '–' : Number(x).toPrecision(digits); }
function scaled(w) {
  const m = Math.max(...w.map(Math.abs));
  return m > 0 ? w.map((x) => x / m) : w;
}

// A blue ramp for probabilities: 0 white, 1 dark blue.
function blue(v, max = 1) {
  const a = Math.max(0, Math.min(1, max > 0 ? v / max : 0));
  return `rgba(21, 101, 192, ${a.toFixed(3)})`;
}

// One matrix (heat map) chart, made on first use and updated in place after.
function matrix(id, xLabels, yLabels, cells, max, tooltip, extra = []) {
  const data = {
    datasets: [{
      type: 'matrix', label: id, data: cells,
      backgroundColor: (c) => blue(c.raw ? c.raw.v : 0, max),
      borderWidth: 0,
      width: ({ chart }) => ((chart.chartArea || {}).width || 0) / xLabels.length,
      height: ({ chart }) => ((chart.chartArea || {}).height || 0) / yLabels.length,
    }, ...extra],
  };
  const scales = {
    x: { type: 'category', labels: xLabels, offset: true, grid: { display: false }, ticks: { maxRotation: 60, autoSkip: true } },
    y: { type: 'category', labels: yLabels, offset: true, reverse: false, grid: { display: false },
      ticks: { autoSkip: yLabels.length > 40, font: { size: 10 } } },
  };
  if (charts[id]) {
    charts[id].data = data;
    charts[id].options.scales = scales;
    charts[id].update('none');
    return;
  }
  charts[id] = new Chart($(id), {
    type: 'matrix', data,
    options: {
      animation: false, maintainAspectRatio: false, scales,
      plugins: { legend: { display: extra.length > 0, labels: { filter: (item) => item.datasetIndex > 0 } },
        tooltip: { callbacks: { title: () => '', label: tooltip } } },
    },
  });
}

function lineOrBar(id, type, labels, datasets, options) {
  const all = { animation: false, maintainAspectRatio: false, ...options };
  if (charts[id]) {
    charts[id].data.labels = labels;
    charts[id].data.datasets = datasets;
    charts[id].options = all;
    charts[id].update('none');
    return;
  }
  charts[id] = new Chart($(id), { type, data: { labels, datasets }, options: all });
}

function showRun(s) {
  const r = s.run;
  const where = r.episode < 0 ? 'waiting for the run' :
    `${s.domain}: episode ${r.episode}${r.controlled ? ' (controlled run)' : ''}, step ${r.step}, t = ${r.sim_seconds.toFixed(1)} s (sim)`;
  $('run').textContent = `${where} · ${r.frames} frames · ${r.episodes_ended} episodes done${r.ended ? ' · run complete' : ''}`;
}

function showCamera(s) {
  const names = s.names;
  $('legend').innerHTML = names.sources.map((n, i) =>
    `<span style="--c:${escapeHtml(s.source_colours[i % s.source_colours.length])}">${escapeHtml(n)}</span>`).join('');
  if (s.camera) {
    const c = s.camera;
    const key = `${c.episode}/${c.step}/${c.frame}/${c.sim_seconds}`;
    if (key !== shownFrame) {
      $('frame').src = `api/frame.png?v=${encodeURIComponent(key)}`;
      shownFrame = key;
    }
    const bySource = names.sources.map(() => 0);
    c.detections.forEach((d) => { bySource[d.source] += 1; });
    $('camera-caption').textContent = `episode ${c.episode}, step ${c.step}, frame ${c.frame} (t = ${c.sim_seconds.toFixed(2)} s): ` +
      `${c.detections.length} detections; most likely from ` +
      names.sources.map((n, i) => `${n} ${bySource[i]}`).join(', ');
  } else if (s.domain === 'gridworld') {
    $('frame').hidden = true;
    $('no-camera').hidden = false;
  }
  if (s.observations) {
    const o = s.observations;
    const symbols = names.symbols.length === o.by_source_symbol[0].length ? names.symbols : o.by_source_symbol[0].map((_, w) => `${w}`);
    lineOrBar('observations-chart', 'bar', symbols, o.by_source_symbol.map((counts, z) => ({
      label: names.sources[z] || `source ${z}`, data: counts, backgroundColor: s.source_colours[z % s.source_colours.length], stack: 'z',
    })), {
      plugins: { title: { display: true, text: `observations of episode ${o.episode}, step ${o.step}, frame ${o.frame}, by most likely source` },
        legend: { display: false } },
      scales: { x: { stacked: true, ticks: { autoSkip: true, maxRotation: 60, font: { size: 9 } } },
        y: { stacked: true, title: { display: true, text: 'observations' }, ticks: { precision: 0 } } },
    });
  }
  if (s.camera || s.observations) filled('panel-camera');
}

function showPosterior(s) {
  const p = s.posterior;
  if (!p || !p.steps) return;
  const steps = Array.from({ length: p.steps }, (_, t) => `${t + 1}`);
  const states = s.names.states.length ? s.names.states : p.state_marginals[0].map((_, i) => `${i}`);
  const cells = [];
  p.state_marginals.forEach((row, t) => row.forEach((v, i) => cells.push({ x: steps[t], y: states[i], v })));
  const extra = [];
  let caption = `episode ${p.episode} after EM iteration ${p.iteration}; log-likelihood ${fmt(p.log_likelihood, 6)}.`;
  if (p.truth) {
    extra.push({ type: 'line', label: 'ground truth', order: -1, showLine: false, pointStyle: 'crossRot', pointRadius: 7, borderWidth: 2,
      borderColor: '#d84315', backgroundColor: '#d84315', data: p.truth.map((x, t) => ({ x: steps[t], y: states[x.state] })) });
    const right = p.most_likely.filter((m, t) => m.state === p.truth[t].state && m.action === p.truth[t].action).length;
    caption += ` Most likely (state, action) is the true one at ${right} of ${p.steps} steps.`;
  } else {
    caption += ' No ground truth for this episode.';
  }
  $('posterior-caption').textContent = caption;
  matrix('posterior-chart', steps, states, cells, 1,
    (c) => (c.raw.v === undefined ? `truth: ${c.raw.y} at step ${c.raw.x}` : `step ${c.raw.x}, ${c.raw.y}: ${fmt(c.raw.v)}`), extra);
  // The actions: Pr(action at step t | ...), the true one marked likewise.
  const actions = s.names.actions.length ? s.names.actions : p.action_marginals[0].map((_, a) => `action ${a}`);
  const acells = [];
  p.action_marginals.forEach((row, t) => row.forEach((v, a) => acells.push({ x: steps[t], y: actions[a], v })));
  const aextra = p.truth ? [{ type: 'line', label: 'true action', order: -1, showLine: false, pointStyle: 'crossRot', pointRadius: 6,
    borderWidth: 2, borderColor: '#d84315', backgroundColor: '#d84315',
    data: p.truth.map((x, t) => ({ x: steps[t], y: actions[x.action] })) }] : [];
  matrix('posterior-actions-chart', steps, actions, acells, 1,
    (c) => (c.raw.v === undefined ? `true action at step ${c.raw.x}: ${c.raw.y}` : `step ${c.raw.x}, ${c.raw.y}: ${fmt(c.raw.v)}`), aextra);
  filled('panel-posterior');
}

function showEm(s) {
  if (!s.em.length) return;
  const it = s.em.map((e) => e.iteration);
  // EM's record never goes down within one prior strength; a newly chosen strength is a
  // new objective, so the line breaks there (docs/MODEL.md "EM's record").
  const newObjective = (ctx) => s.em[ctx.p1DataIndex].prior_strength !== s.em[ctx.p0DataIndex].prior_strength;
  const datasets = [{ label: 'EM objective', data: s.em.map((e) => e.log_likelihood), borderColor: '#1565c0', yAxisID: 'll', pointRadius: 2,
    segment: { borderColor: (ctx) => (newObjective(ctx) ? 'rgba(0,0,0,0)' : undefined) } }];
  const hasIle = s.em.some((e) => e.ile !== null);
  if (hasIle) datasets.push({ label: 'ILE (true reward)', data: s.em.map((e) => e.ile), borderColor: '#d84315', yAxisID: 'ile', pointRadius: 2 });
  lineOrBar('em-chart', 'line', it, datasets, {
    scales: {
      x: { title: { display: true, text: 'EM iteration' } },
      ll: { position: 'left', title: { display: true, text: 'log Pr(observations | θ, O) + log prior' } },
      ile: { position: 'right', display: hasIle, min: 0, title: { display: true, text: 'ILE' }, grid: { drawOnChartArea: false } },
    },
  });
  const last = s.em[s.em.length - 1];
  const strength = last.prior_strength > 0 ? ` (prior strength ${fmt(last.prior_strength)}; a new strength breaks the line)` : '';
  $('em-caption').textContent = `${s.em.length} iterations, ${fmt(last.seconds, 3)} s; EM objective ${fmt(last.log_likelihood, 8)}${strength}` +
    (last.ile !== null ? `, ILE ${fmt(last.ile)}` : '') + (s.reward && s.reward.final ? ' · finished' : ' · learning…');
  filled('panel-em');
}

function showEstimates(s) {
  const es = s.estimates || [];
  if (!es.length) return;
  const n = es.map((e) => e.demonstrations);
  const datasets = [{ label: 'confidence', data: es.map((e) => e.confidence), borderColor: '#2e7d32', yAxisID: 'p', pointRadius: 3 }];
  const hasIle = es.some((e) => e.ile_relative !== null);
  if (hasIle) datasets.push({ label: 'relative ILE (true reward)', data: es.map((e) => e.ile_relative), borderColor: '#d84315', yAxisID: 'ile', pointRadius: 3 });
  lineOrBar('estimates-chart', 'line', n, datasets, {
    scales: {
      x: { title: { display: true, text: 'demonstrations' } },
      p: { position: 'left', min: 0, max: 1, title: { display: true, text: 'confidence' } },
      ile: { position: 'right', display: hasIle, min: 0, title: { display: true, text: 'ILE / ||V*||₁' }, grid: { drawOnChartArea: false } },
    },
  });
  const last = es[es.length - 1];
  $('estimates-caption').textContent = `after ${last.demonstrations} demonstrations: confidence ${fmt(last.confidence)}` +
    (last.ile_relative !== null ? `, relative ILE ${fmt(last.ile_relative)}` : '') + `; the update took ${fmt(last.seconds, 2)} s`;
  filled('panel-estimates');
}

function showTheta(s) {
  const th = s.theta;
  if (!th) return;
  const labels = s.names.features.length === th.learned.length ? s.names.features : th.learned.map((_, k) => `feature ${k}`);
  const datasets = [{ label: th.final ? 'learned θ (final)' : 'learned θ (so far)', data: scaled(th.learned), backgroundColor: '#1565c0' }];
  if (th.true) datasets.push({ label: 'true weights', data: scaled(th.true), backgroundColor: '#ef6c00' });
  lineOrBar('theta-chart', 'bar', labels, datasets, { scales: { y: { min: -1, max: 1, title: { display: true, text: 'w / max |w|' } } } });
  $('theta-caption').textContent = `θ = [${th.learned.map((x) => fmt(x)).join(', ')}]` + (th.true ? `; true [${th.true.join(', ')}]` : '');
  filled('panel-theta');
}

function showModel(s) {
  const m = s.model;
  if (!m) return;
  const names = s.names;
  const symbols = names.symbols.length === m.subject[0].length ? names.symbols : m.subject[0].map((_, w) => `${w}`);
  const pairs = m.subject.map((_, r) => {
    const st = names.states[Math.floor(r / m.num_actions)];
    const ac = names.actions[r % m.num_actions];
    return st && ac ? `${st} · ${ac}` : `pair ${r}`;
  });
  const cells = [];
  m.subject.forEach((row, r) => row.forEach((v, w) => cells.push({ x: symbols[w], y: pairs[r], v })));
  const top = (rows) => Math.max(1e-12, ...rows.map((row) => Math.max(...row)));
  matrix('subject-chart', symbols, pairs, cells, top(m.subject), (c) => `${c.raw.y}: Pr(${c.raw.x}) = ${fmt(c.raw.v)}`);
  if (m.confounders.length) {
    const sources = m.confounders.map((_, e) => names.sources[e + 1] || `element ${e + 1}`);
    const ccells = [];
    m.confounders.forEach((row, e) => row.forEach((v, w) => ccells.push({ x: symbols[w], y: sources[e], v })));
    matrix('confounder-chart', symbols, sources, ccells, top(m.confounders), (c) => `${c.raw.y}: Pr(${c.raw.x}) = ${fmt(c.raw.v)}`);
  }
  $('model-caption').textContent = `after EM iteration ${m.iteration}: the subject (left, one row per state · action) and the ` +
    `${m.confounders.length} confounding elements (right); darker = more likely (each map scaled to its largest value).`;
  filled('panel-model');
}

// Learned eta: per context (a labeller rule, or each distinct stated eta), the subject's
// share as the labeller stated it and as learned, for the contexts covering the most
// observations; the whole distributions in the tooltip.
function showEta(s) {
  const e = s.eta;
  if (!e || !e.contexts.length) return;
  const names = s.names.sources;
  const count = (x) => (x >= 100 ? `${Math.round(x)}` : fmt(x, 3));
  const labels = e.contexts.map((c) => `${s.names.contexts[c.context] || `context ${c.context}`} (${count(c.observations)})`);
  const whole = (row) => row.map((v, z) => `${names[z] || `source ${z}`} ${fmt(v, 2)}`).join(', ');
  lineOrBar('eta-chart', 'bar', labels, [
    { label: 'stated η(subject)', data: e.contexts.map((c) => c.stated[0]), backgroundColor: '#9e9e9e' },
    { label: 'learned η(subject)', data: e.contexts.map((c) => c.learned[0]), backgroundColor: '#1565c0' },
  ], {
    scales: { y: { min: 0, max: 1, title: { display: true, text: 'η(subject)' } } },
    plugins: { tooltip: { callbacks: { afterLabel: (item) => {
      const c = e.contexts[item.dataIndex];
      return item.datasetIndex === 0 ? `stated: ${whole(c.stated)}` : `learned: ${whole(c.learned)}`;
    } } } },
  });
  $('eta-caption').textContent = `after EM iteration ${e.iteration}: ${e.contexts.length} of the ${e.with_observations} contexts ` +
    `with observations (most observations first; in brackets). Grey: the subject's share of η as stated; blue: as learned.`;
  filled('panel-eta');
}

function showServices(s) {
  if (!s.services.length) return;
  $('services').querySelector('tbody').innerHTML = s.services.map((x) => {
    const age = x.seconds_since_heartbeat;
    const done = x.state === 'done' || x.state === 'stopped';
    return `<tr><td>${escapeHtml(x.service)}</td><td>${escapeHtml(x.id)}</td><td>${escapeHtml(x.state)}</td>` +
      `<td class="${age > 3 && !done ? 'stale' : ''}">${age.toFixed(1)} s ago</td><td>${x.messages_in}</td><td>${x.messages_out}</td>` +
      `<td class="${x.bad_messages > 0 ? 'bad' : ''}">${x.bad_messages}</td><td>${x.gaps}</td>` +
      `<td class="${x.restarts > 0 ? 'stale' : ''}">${x.restarts}</td>` +
      `<td class="${x.authenticated ? '' : 'bad'}">${x.authenticated ? 'yes' : 'no'}</td><td>${escapeHtml(x.detail)}</td></tr>`;
  }).join('');
  $('estep-caption').textContent = s.estep ? `E-step over the bus: ${s.estep.retried_blocks} blocks re-asked, ` +
    `${s.estep.local_blocks} computed by the optimiser itself.` : '';
  filled('panel-services');
}

function escapeHtml(t) {
  return String(t).replace(/[&<>"]/g, (ch) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[ch]));
}

// One panel's failure (data it cannot draw) must not stop the others.
function draw(show, s) {
  try {
    show(s);
  } catch (e) {
    console.error(`${show.name}: ${e}`);
  }
}

async function poll() {
  try {
    const response = await fetch('api/state', { cache: 'no-store' });
    const s = await response.json();
    $('connection').textContent = '';
    if (s.version !== shownVersion) {
      shownVersion = s.version;
      for (const show of [showRun, showCamera, showPosterior, showEm, showEstimates, showTheta, showModel, showEta]) draw(show, s);
    }
    draw(showServices, s);  // heartbeat ages change with the clock
  } catch (e) {
    $('connection').textContent = 'not connected to hbirl-dashboard';
  }
  setTimeout(poll, POLL_MS);
}

poll();
