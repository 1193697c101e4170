// The dashboard of `idrig serve`: one page, views chosen by the URL hash, data from /api/.
// Read-only: every request is a GET.
import { linePlot, scatterPlot, orderAxis } from './plots.js';

const view = document.getElementById('view');
let refreshTimer = null;

async function api(path) {
  const r = await fetch('/api/' + path);
  const body = await r.json();
  if (!r.ok) throw new Error(body.error || r.statusText);
  return body;
}

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c instanceof Node ? c : document.createTextNode(c ?? ''));
  return e;
}

const short = (text, n = 34) => (text && text.length > n ? el('span', { title: text }, text.slice(0, n - 1) + '…') : text || '');
const num = (v, p = 4) => (v === null || v === undefined || !Number.isFinite(v) ? '-' : String(+v.toPrecision(p)));
const poles = (list) => list.map(([re, im]) => (Math.abs(im) < 1e-9 ? num(re) : `${num(re)}${im < 0 ? '−' : '+'}${num(Math.abs(im))}j`)).join(', ');

// columns: [[header, row => value, className]]
function table(rows, columns, { id, onclick, selected } = {}) {
  const t = el('table', id ? { id } : {});
  t.append(el('tr', {}, ...columns.map(([h]) => el('th', {}, h))));
  for (const r of rows) {
    const tr = el('tr', onclick ? { onclick: () => onclick(r), style: 'cursor:pointer' } : {});
    if (selected && selected(r)) tr.className = 'selected';
    for (const [, f, cls] of columns) {
      const v = f(r);
      tr.append(el('td', cls ? { class: cls } : {}, v));
    }
    t.append(tr);
  }
  return t;
}

function showError(e) {
  view.append(el('p', { class: 'error' }, String(e.message || e)));
}

// ---- rigs and live services
async function rigsView() {
  const [summary, rigs] = await Promise.all([api('summary'), api('rigs')]);
  view.append(el('h2', {}, 'Rigs'),
    el('p', {}, `catalogue ${summary.db}: ${summary.models ?? 0} models, ${summary.experiments ?? 0} experiments, ${summary.diagnoses ?? 0} gap reports; experiment store ${summary.experiments_store}${summary.store_present ? '' : ' (absent)'}`),
    table(rigs.rigs, [['rig', (r) => r.rig_id], ['experiments', (r) => r.experiments ?? 0, 'num'], ['models', (r) => r.models ?? 0, 'num'],
      ['last experiment (UTC)', (r) => r.last_experiment_utc ?? '-'], ['last model (UTC)', (r) => r.last_model_utc ?? '-']], { id: 'rigs-table' }));
  const live = el('div', { id: 'live' });
  view.append(el('h2', {}, 'Services (live)'), live);
  const draw = (l) => {
    live.replaceChildren();
    if (!l.url) { live.append(el('p', { class: 'muted' }, 'not listening: start with --url LCM_URL to see the services and experiments live')); return; }
    if (!l.listening) { live.append(el('p', { class: 'error' }, `cannot listen on ${l.url}: ${l.error}`)); return; }
    live.append(el('p', { class: 'muted' }, `status heard on ${l.url} (refreshed every 2 s)`),
      table(l.services, [['service', (s) => s.instance_id], ['state', (s) => s.state], ['host', (s) => s.host], ['pid', (s) => s.pid, 'num'],
        ['up [s]', (s) => num(s.uptime_s), 'num'], ['heard [s ago]', (s) => num(s.age_s, 2), 'num'], ['received', (s) => s.received, 'num'],
        ['sent', (s) => s.published, 'num'], ['dropped', (s) => s.dropped, 'num'], ['refused', (s) => s.refused, 'num']]),
      el('h3', {}, 'Experiments in progress'),
      table(l.experiments, [['rig', (e) => e.rig_id], ['experiment', (e) => e.experiment_id], ['from', (e) => e.source], ['state', (e) => e.state],
        ['progress', (e) => `${e.samples_done}/${e.samples_total} samples (${e.samples_total ? Math.round(100 * e.samples_done / e.samples_total) : 0} %)`],
        ['signal', (e) => e.signal_spec], ['message', (e) => e.message]]));
  };
  draw(rigs.live);
  refreshTimer = setInterval(async () => { try { draw((await api('rigs')).live); } catch (e) { /* keep the last view */ } }, 2000);
}

// ---- experiments
async function experimentsView(rig, id) {
  const list = await api('experiments');
  view.append(el('h2', {}, 'Experiments'),
    table(list, [['rig', (e) => e.rig_id], ['experiment', (e) => String(e.experiment_id)], ['signal', (e) => short(e.signal_spec, 48)], ['fs [Hz]', (e) => num(e.sample_rate_hz), 'num'],
      ['samples', (e) => e.samples_total, 'num'], ['state', (e) => e.state], ['started (UTC)', (e) => e.start_utc ?? '-'],
      ['blocks stored', (e) => (e.in_store ? `${e.blocks_stored}/${e.blocks_total}${e.missing_blocks ? `, ${e.missing_blocks} missing` : ''}` : 'not in the store')]],
    { id: 'experiments-table', onclick: (e) => { location.hash = `experiments/${e.rig_id}/${e.experiment_id}`; }, selected: (e) => String(e.experiment_id) === id }));
  if (!id) { view.append(el('p', { class: 'muted' }, 'click an experiment to plot its signals')); return; }
  const s = await api(`experiments/${rig}/${id}/signals?max=3000`);
  const base = `/api/experiments/${rig}/${id}/export`;
  view.append(el('h3', {}, `experiment ${id}: ${s.signal_spec} — ${s.samples} samples at Ts ${s.Ts} s`),
    el('p', {}, 'export: ', el('a', { href: base + '.csv', download: '' }, 'CSV'), ' · ', el('a', { href: base + '.mat', download: '' }, 'MATLAB .mat'),
      s.stride > 1 ? el('span', { class: 'muted' }, ` (plotted every ${s.stride}th sample)`) : ''));
  const row = el('div', { class: 'row' });
  view.append(row);
  linePlot(row, { title: 'input u', x: s.t, xLabel: 'time [s]', yLabel: 'u [actuator units]', series: s.u.map((u, i) => ({ label: `u${i + 1}`, y: u })) });
  linePlot(row, { title: 'output y', x: s.t, xLabel: 'time [s]', yLabel: 'y [sensor units]', series: s.y.map((y, i) => ({ label: `y${i + 1}`, y, colour: '#D55E00' })) });
}

// ---- models: list, filter, detail, compare
function bodePlots(parent, bodes, labels) {
  const b0 = bodes[0];
  const series = bodes.map((b, i) => ({ label: labels[i], y: b.mag_db }));
  const phase = bodes.map((b, i) => ({ label: labels[i], y: b.phase_deg }));
  const bands = [];
  let note = '';
  if (bodes.length === 1 && b0.band) {
    series.push({ label: '+2σ', y: b0.band.mag_db_hi, colour: '#9ab', width: 1 }, { label: '−2σ', y: b0.band.mag_db_lo, colour: '#9ab', width: 1 });
    phase.push({ label: '+2σ', y: b0.band.phase_deg_hi, colour: '#9ab', width: 1 }, { label: '−2σ', y: b0.band.phase_deg_lo, colour: '#9ab', width: 1 });
    bands.push([2, 3, 'rgba(0,114,178,0.15)']);
    note = 'band: ' + b0.band.note;
  } else if (bodes.length === 1) {
    note = `no confidence band: ${b0.no_band || 'no covariance'}`;
  }
  // Compared models share one frequency grid only if equal; else each is drawn on the first's grid.
  const x = b0.omega;
  const align = (b, y) => (b.omega.length === x.length ? y : x.map((w) => y[b.omega.findIndex((v) => v >= w)] ?? null));
  series.forEach((s, i) => { if (i < bodes.length) s.y = align(bodes[i], s.y); });
  phase.forEach((s, i) => { if (i < bodes.length) s.y = align(bodes[i], s.y); });
  const div = el('div', { id: 'bode' });
  parent.append(div);
  linePlot(div, { kind: 'bode-magnitude', title: 'Bode magnitude', note, x, logX: true, xLabel: 'ω [rad/s]', yLabel: '|W(jω)| [dB]', series, bands });
  linePlot(div, { kind: 'bode-phase', title: 'Bode phase', x, logX: true, xLabel: 'ω [rad/s]', yLabel: '∠W(jω) [deg]', series: phase, bands: bands.length ? [[2, 3, 'rgba(0,114,178,0.15)']] : [] });
}

async function modelDetail(parent, id) {
  const [m, bode, step, pz, stab] = await Promise.all([api(`models/${id}`), api(`models/${id}/bode`), api(`models/${id}/step`), api(`models/${id}/poles`), api(`models/${id}/stabilisation`)]);
  parent.append(el('h2', {}, `model ${m.model_id}: ${m.method} on rig ${m.rig_id}`),
    table([
      ['experiment', `${m.experiment_id} (${m.signal_spec})`], ['method and options', `${m.method} ${JSON.stringify(m.options)}`],
      ['data', `${m.n_samples} samples at Ts ${m.sample_time_s} s, sha256 ${m.data_hash.slice(0, 16)}…`],
      ['worker', `${m.worker_id}, ${num(m.compute_s, 3)} s, idrig ${m.software_version}`], ['stored (UTC)', m.created_utc],
      ['fit on the record', `${num(m.record_fit_percent)} % (the method's own: ${num(m.fit_percent)} %)`], ['status', `${m.status} ${m.report_message || ''}`],
      ['poles [rad/s]', poles(m.poles)], ['DC gain', num(m.dc_gain)],
    ], [['lineage', (r) => r[0]], ['', (r) => r[1]]], { id: 'lineage' }));
  const row = el('div', { class: 'row' });
  parent.append(row);
  bodePlots(row, [bode], [`model ${id}`]);
  const row2 = el('div', { class: 'row' });
  parent.append(row2);
  linePlot(row2, { kind: 'step', title: 'step response', x: step.t, xLabel: 'time [s]', yLabel: 'y for a unit step', series: [{ label: `model ${id}`, y: step.y }] });
  const discrete = pz.domain === 'discrete';
  scatterPlot(row2, { title: `poles and zeros (${pz.domain}${discrete ? ', z-plane with the unit circle' : ', s-plane'})`, xLabel: discrete ? 'Re z' : 'Re s [rad/s]', yLabel: discrete ? 'Im z' : 'Im s [rad/s]',
    circle: discrete, equal: true, groups: [{ label: 'poles', points: pz.poles, marker: 'x' }, { label: 'zeros', points: pz.zeros, marker: 'o', colour: '#D55E00' }] });
  if (stab.points.length) {
    scatterPlot(parent, { title: 'stabilisation diagram', width: 760, xLabel: 'frequency [Hz]', yLabel: 'model order p', groups: [
      { label: 'stable in frequency and damping', points: stab.points.filter((p) => p.stable).map((p) => [p.frequency_hz, p.p]), marker: 'dot', colour: '#009E73' },
      { label: 'stable in frequency', points: stab.points.filter((p) => !p.stable && p.stable_frequency).map((p) => [p.frequency_hz, p.p]), marker: 'o', colour: '#0072B2' },
      { label: 'new', points: stab.points.filter((p) => !p.stable_frequency).map((p) => [p.frequency_hz, p.p]), marker: 'x', colour: '#999' }] });
  }
}

async function compareView(parent, a, b) {
  const [c, ba, bb] = await Promise.all([api(`compare?a=${a}&b=${b}`), api(`models/${a}/bode`), api(`models/${b}/bode`)]);
  parent.append(el('h2', {}, `model ${a} and model ${b}`),
    table(c.rows, [['', (r) => r.name + (r.unit && r.unit !== '1' ? ` [${r.unit}]` : '')], [`model ${a}`, (r) => r.a, 'num'], [`model ${b}`, (r) => r.b, 'num'], ['difference (b − a)', (r) => r.difference, 'num']], { id: 'compare-table' }));
  bodePlots(parent, [ba, bb], [`model ${a} (${ba.method})`, `model ${b} (${bb.method})`]);
}

async function modelsView(id, query) {
  const rig = query.get('rig') || '', method = query.get('method') || '';
  const list = await api(`models?rig=${encodeURIComponent(rig)}&method=${encodeURIComponent(method)}`);
  const picked = new Set((query.get('compare') || '').split(',').filter(Boolean));
  const rigIn = el('input', { value: rig, placeholder: 'rig', size: 8 }), methodIn = el('input', { value: method, placeholder: 'method', size: 14 });
  const go = () => { location.hash = `models?rig=${encodeURIComponent(rigIn.value)}&method=${encodeURIComponent(methodIn.value)}`; };
  view.append(el('h2', {}, 'Models'), el('div', { class: 'controls' }, 'filter: ', rigIn, methodIn, el('button', { onclick: go }, 'apply'),
    el('span', { class: 'muted' }, 'click a row for its plots; tick two to compare')));
  const columns = [
    ['compare', (m) => { const c = el('input', { type: 'checkbox' }); c.checked = picked.has(String(m.model_id));
      c.addEventListener('click', (ev) => { ev.stopPropagation(); c.checked ? picked.add(String(m.model_id)) : picked.delete(String(m.model_id));
        if (picked.size === 2) location.hash = `models?compare=${[...picked].join(',')}`; }); return c; }],
    ['id', (m) => String(m.model_id), 'num'], ['rig', (m) => m.rig_id], ['experiment', (m) => String(m.experiment_id)], ['signal', (m) => short(m.signal_spec)],
    ['method', (m) => m.method], ['fit %', (m) => num(m.record_fit_percent ?? m.fit_percent), 'num'], ['order', (m) => num(m.order), 'num'],
    ['DC gain', (m) => num(m.dc_gain), 'num'], ['poles [rad/s]', (m) => poles(m.poles)], ['worker', (m) => m.worker_id], ['stored (UTC)', (m) => m.created_utc]];
  view.append(table(list, columns, { id: 'models-table', onclick: (m) => { location.hash = `models/${m.model_id}`; }, selected: (m) => String(m.model_id) === id }));
  if (!list.length) view.append(el('p', { class: 'muted' }, 'no model matches'));
  if (picked.size === 2) { const [a, b] = [...picked]; await compareView(view, a, b); } else if (id) await modelDetail(view, id);
}

// ---- history of a parameter
async function historyView(query) {
  const models = await api('models');
  const rigs = [...new Set(models.map((m) => m.rig_id))];
  const params = [...new Set(models.flatMap((m) => m.metrics))].sort();
  const rig = query.get('rig') || rigs[0] || '', param = query.get('param') || 'wn_1', method = query.get('method') || '';
  const select = (values, current) => { const s = el('select'); for (const v of values) { const o = el('option', { value: v }, v || '(every method)'); if (v === current) o.selected = true; s.append(o); } return s; };
  const rigSel = select(rigs, rig), paramSel = select(params, param), methodSel = select(['', ...new Set(models.map((m) => m.method))], method);
  const go = () => { location.hash = `history?rig=${rigSel.value}&param=${paramSel.value}&method=${methodSel.value}`; };
  [rigSel, paramSel, methodSel].forEach((s) => s.addEventListener('change', go));
  view.append(el('h2', {}, 'History of a parameter'), el('div', { class: 'controls' }, 'rig ', rigSel, ' parameter ', paramSel, ' method ', methodSel));
  if (!rig) { view.append(el('p', { class: 'muted' }, 'no rig in the catalogue yet')); return; }
  const h = await api(`history?rig=${encodeURIComponent(rig)}&param=${encodeURIComponent(param)}&method=${encodeURIComponent(method)}`);
  if (!h.count) { view.append(el('p', { class: 'muted' }, `no model of rig ${rig} has ${param}`)); return; }
  // One x per model. Models stored close together (closer than 1/100 of the span) would overlap on
  // a time axis: then x is the storage order, each tick labelled with the storage time.
  const points = h.series.flatMap((s) => s.points).sort((a, b) => a.t - b.t);
  const span = points[points.length - 1].t - points[0].t;
  const closest = Math.min(...points.slice(1).map((p, i) => p.t - points[i].t));
  const ordinal = points.length > 1 && closest < span / 100;
  const x = ordinal ? points.map((p, i) => i) : points.map((p) => p.t);
  const series = h.series.map((s) => ({ label: s.method, points: true, y: points.map((p) => (s.points.some((q) => q.model_id === p.model_id) ? p.value : null)) }));
  const sameSecond = points.some((p, i) => i > 0 && Math.floor(p.t) === Math.floor(points[i - 1].t));
  const ms = (p) => (sameSecond ? '.' + String(Math.floor((p.utime / 1000) % 1000)).padStart(3, '0') : '');
  const labels = points.map((p) => (span > 43200 ? p.utc.slice(5) : p.utc.slice(11)) + ms(p));
  const div = el('div', { id: 'history' });
  view.append(div);
  linePlot(div, { kind: 'history', title: `${param} of rig ${rig}, one series per method`, width: 900, height: 360, x, time: !ordinal,
    xLabel: ordinal ? 'models in storage order, labelled with the storage time (UTC)' : 'time stored (UTC)', yLabel: `${param} [${h.unit}]`,
    xValues: ordinal ? orderAxis(labels) : undefined, xSplits: ordinal ? () => x : undefined, xRange: ordinal ? [-0.5, x.length - 0.5] : undefined, series,
    note: `${h.count} models from ${points[0].utc} to ${points[points.length - 1].utc} UTC` });
  view.append(table(points, [['model', (p) => String(p.model_id), 'num'], ['method', (p) => h.series.find((s) => s.points.some((q) => q.model_id === p.model_id)).method],
    ['stored (UTC)', (p) => p.utc], [`${param} [${h.unit}]`, (p) => num(p.value, 6), 'num']]));
}

// ---- gap reports
async function gapsView(id) {
  const list = await api('gaps');
  view.append(el('h2', {}, 'Gap reports'), table(list, [['report', (g) => String(g.report_id), 'num'], ['rig', (g) => g.rig_id], ['experiment', (g) => String(g.experiment_id)],
    ['verdict', (g) => g.verdict.effect], ['confidence', (g) => num(g.verdict.confidence, 3), 'num'], ['NRMSE before → after', (g) => `${num(g.verdict.nrmse_before, 3)} → ${num(g.verdict.nrmse_after, 3)}`],
    ['stored (UTC)', (g) => g.created_utc]], { id: 'gaps-table', onclick: (g) => { location.hash = `gaps/${g.report_id}`; }, selected: (g) => String(g.report_id) === id }));
  if (!list.length) { view.append(el('p', { class: 'muted' }, 'no gap diagnosis stored (idrig models request --method gap-diagnose …)')); return; }
  id = id || String(list[0].report_id);
  const [g, svgs] = await Promise.all([api(`gaps/${id}`), api(`gaps/${id}/plots`)]);
  view.append(el('h3', {}, `report ${id}: where, which, how far`), el('pre', {}, g.text));
  const row = el('div', { class: 'row', id: 'gap-plots' });
  view.append(row);
  // where (frequency, amplitude, state, time), then which and how far (the ranking)
  const order = ['gap_frequency.svg', 'gap_amplitude.svg', 'gap_state.svg', 'gap_time.svg', 'gap_ranking.svg'];
  const names = Object.keys(svgs).sort((a, b) => (order.indexOf(a) + 99 * (order.indexOf(a) < 0)) - (order.indexOf(b) + 99 * (order.indexOf(b) < 0)));
  for (const [name, svg] of names.map((n) => [n, svgs[n]])) {
    const d = el('div', { class: 'plot svg-plot', 'data-name': name });
    d.innerHTML = svg;
    d.dataset.points = String(d.querySelectorAll('rect.bar').length);
    row.append(d);
  }
}

// ---- jobs
async function jobsView() {
  const list = await api('jobs');
  view.append(el('h2', {}, 'Identification jobs'), table(list, [['request', (j) => String(j.request_id)], ['rig', (j) => j.rig_id], ['experiment', (j) => String(j.experiment_id)],
    ['method', (j) => j.method], ['state', (j) => j.state], ['worker', (j) => j.worker_id], ['attempts', (j) => j.attempts, 'num'], ['requested (UTC)', (j) => j.created_utc],
    ['message (why it failed)', (j) => j.message]], { id: 'jobs-table' }));
}

async function route() {
  clearInterval(refreshTimer);
  view.replaceChildren();
  const [path, q] = (location.hash.slice(1) || 'models').split('?');
  const parts = path.split('/');
  const query = new URLSearchParams(q || '');
  document.querySelectorAll('nav a').forEach((a) => a.classList.toggle('active', a.getAttribute('href') === '#' + parts[0]));
  try {
    if (parts[0] === 'rigs') await rigsView();
    else if (parts[0] === 'experiments') await experimentsView(parts[1], parts[2]);
    else if (parts[0] === 'history') await historyView(query);
    else if (parts[0] === 'gaps') await gapsView(parts[1]);
    else if (parts[0] === 'jobs') await jobsView();
    else await modelsView(parts[1], query);
  } catch (e) {
    showError(e);
  }
  document.body.dataset.ready = location.hash || '#';
}

api('summary').then((s) => { document.getElementById('source').textContent = `${s.db} · idrig ${s.version}${s.url ? ' · live ' + s.url : ''}`; }).catch(() => {});
window.addEventListener('hashchange', route);
route();
