// Plots of the dashboard: uPlot for lines (signals, Bode, step, history), a small SVG scatter for
// the pole-zero map and the stabilisation diagram. Every plot element gets data-points = the
// number of finite points it draws (the browser test checks it, and the pixels).
import uPlot from './uPlot.esm.js';

export const COLOURS = ['#0072B2', '#D55E00', '#009E73', '#CC79A7', '#E69F00', '#56B4E9', '#000000'];

function finiteCount(arrays) {
  let n = 0;
  for (const a of arrays) for (const v of a) if (v !== null && Number.isFinite(v)) n++;
  return n;
}

function box(parent, title, note) {
  const div = document.createElement('div');
  div.className = 'plot';
  if (title) {
    const h = document.createElement('h3');
    h.textContent = title;
    div.appendChild(h);
  }
  parent.appendChild(div);
  if (note) {
    const p = document.createElement('p');
    p.className = 'note';
    p.textContent = note;
    div.appendChild(p);
  }
  return div;
}

// opts: {title, note, x: [...], xLabel, yLabel, series: [{label, y, colour, dash, points, width}],
//        logX, time, xValues (axis tick formatter), xRange [min, max], bands: [[hiIndex, loIndex, fill]], width, height}
export function linePlot(parent, opts) {
  const div = box(parent, opts.title, opts.note);
  div.classList.add('uplot-box');
  const series = [{ label: opts.xLabel }];
  opts.series.forEach((s, i) => series.push({
    label: s.label,
    stroke: s.colour || COLOURS[i % COLOURS.length],
    width: s.width || 1.6,
    dash: s.dash,
    fill: s.fill,
    spanGaps: true,
    points: { show: s.points ?? false, size: 7 },
  }));
  const axes = [
    { label: opts.xLabel, values: opts.xValues, space: opts.time ? 80 : 50, rotate: 0 },
    { label: opts.yLabel, size: 70 },
  ];
  if (opts.xSplits) axes[0].splits = opts.xSplits;
  const u = new uPlot({
    width: opts.width || 760, height: opts.height || 300,
    scales: { x: opts.logX ? { time: false, distr: 3, log: 10 } : { time: !!opts.time, ...(opts.xRange ? { range: opts.xRange } : {}) } },
    series, axes,
    bands: (opts.bands || []).map(([a, b, fill]) => ({ series: [a, b], fill })),
    legend: { show: true },
  }, [opts.x, ...opts.series.map((s) => s.y)], div);
  div.dataset.points = String(finiteCount(opts.series.map((s) => s.y)));
  div.dataset.kind = opts.kind || 'line';
  return u;
}

function nice(lo, hi) {
  if (!(hi > lo)) { lo -= 1; hi += 1; }
  const pad = 0.08 * (hi - lo);
  return [lo - pad, hi + pad];
}

function ticks(lo, hi, target = 6) {
  const raw = (hi - lo) / target, mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw * (1 - 1e-9));
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) out.push(Math.abs(v) < 1e-12 ? 0 : v);
  return out;
}

const fmt = (v) => (Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-3 && v !== 0) ? v.toExponential(1) : String(+v.toPrecision(4)));

// opts: {title, note, xLabel, yLabel, groups: [{label, points: [[x, y]], marker: 'x'|'o'|'dot', colour}],
//        circle (draw the unit circle), equal (same scale on x and y)}
export function scatterPlot(parent, opts) {
  const div = box(parent, opts.title, opts.note);
  const W = opts.width || 560, H = opts.height || 420, L = 70, R = 20, T = 16, B = 50 + 16 * opts.groups.length;
  const all = opts.groups.flatMap((g) => g.points);
  if (opts.circle) all.push([-1, -1], [1, 1]);
  let [x0, x1] = nice(Math.min(...all.map((p) => p[0])), Math.max(...all.map((p) => p[0])));
  let [y0, y1] = nice(Math.min(...all.map((p) => p[1])), Math.max(...all.map((p) => p[1])));
  const pw = W - L - R, ph = H - T - B;
  if (opts.equal) {  // same units per pixel on both axes
    const s = Math.max((x1 - x0) / pw, (y1 - y0) / ph);
    const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
    [x0, x1] = [cx - s * pw / 2, cx + s * pw / 2];
    [y0, y1] = [cy - s * ph / 2, cy + s * ph / 2];
  }
  const sx = (v) => L + pw * (v - x0) / (x1 - x0), sy = (v) => T + ph - ph * (v - y0) / (y1 - y0);
  let s = `<svg xmlns="http://www.w3.org/2000/svg" width="${W}" height="${H}" font-size="11" font-family="sans-serif">`;
  s += `<rect x="${L}" y="${T}" width="${pw}" height="${ph}" fill="white" stroke="black"/>`;
  for (const v of ticks(x0, x1)) s += `<line x1="${sx(v)}" x2="${sx(v)}" y1="${T}" y2="${T + ph}" stroke="#e4e4e4"/><text x="${sx(v)}" y="${T + ph + 14}" text-anchor="middle">${fmt(v)}</text>`;
  for (const v of ticks(y0, y1)) s += `<line x1="${L}" x2="${L + pw}" y1="${sy(v)}" y2="${sy(v)}" stroke="#e4e4e4"/><text x="${L - 5}" y="${sy(v) + 4}" text-anchor="end">${fmt(v)}</text>`;
  if (x0 < 0 && x1 > 0) s += `<line x1="${sx(0)}" x2="${sx(0)}" y1="${T}" y2="${T + ph}" stroke="#999"/>`;
  if (y0 < 0 && y1 > 0) s += `<line x1="${L}" x2="${L + pw}" y1="${sy(0)}" y2="${sy(0)}" stroke="#999"/>`;
  if (opts.circle) s += `<ellipse cx="${sx(0)}" cy="${sy(0)}" rx="${sx(1) - sx(0)}" ry="${sy(0) - sy(1)}" fill="none" stroke="#888" stroke-dasharray="4,3"/>`;
  s += `<text x="${L + pw / 2}" y="${T + ph + 34}" text-anchor="middle">${opts.xLabel}</text>`;
  s += `<text transform="translate(16,${T + ph / 2}) rotate(-90)" text-anchor="middle">${opts.yLabel}</text>`;
  opts.groups.forEach((g, i) => {
    const c = g.colour || COLOURS[i % COLOURS.length];
    for (const [x, y] of g.points) {
      const X = sx(x), Y = sy(y);
      const tip = `<title>${g.label}: ${fmt(x)}, ${fmt(y)}</title>`;
      if (g.marker === 'x') s += `<g class="mark"><path d="M${X - 5},${Y - 5}L${X + 5},${Y + 5}M${X - 5},${Y + 5}L${X + 5},${Y - 5}" stroke="${c}" stroke-width="2"/>${tip}</g>`;
      else if (g.marker === 'o') s += `<circle class="mark" cx="${X}" cy="${Y}" r="5" fill="none" stroke="${c}" stroke-width="2">${tip}</circle>`;
      else s += `<circle class="mark" cx="${X}" cy="${Y}" r="3.5" fill="${c}">${tip}</circle>`;
    }
    const ly = T + ph + 50 + 16 * i;
    s += `<circle cx="${L + 10}" cy="${ly - 4}" r="4" fill="${g.marker === 'o' ? 'none' : c}" stroke="${c}" stroke-width="2"/><text x="${L + 22}" y="${ly}">${g.label}</text>`;
  });
  s += '</svg>';
  const holder = document.createElement('div');
  holder.innerHTML = s;
  div.appendChild(holder);
  div.dataset.points = String(opts.groups.reduce((n, g) => n + g.points.length, 0));
  div.dataset.kind = 'scatter';
  return div;
}

// Ticks on a storage-order axis: index -> the storage time of that model.
export function orderAxis(labels) {
  return (u, splits) => splits.map((v) => (Number.isInteger(v) && labels[v] !== undefined ? labels[v] : ''));
}
