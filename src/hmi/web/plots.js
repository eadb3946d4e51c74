// Live plots (uPlot): path speed against the programmed feed, the overrides, the spindle load
// against its target ([adaptive] target_load_pct).
// Fixed-length windows of the last WINDOW_S seconds: memory does not grow with the run.
const WINDOW_S = 30;

function makePlot(el, title, series, yRange) {
  const opts = {
    title, width: Math.max(el.clientWidth, 200), height: 150,
    scales: { x: { time: false }, y: yRange ? { range: yRange } : {} },
    axes: [{ stroke: '#9aa3ad', grid: { stroke: '#2c3138' }, label: 's' },
           { stroke: '#9aa3ad', grid: { stroke: '#2c3138' }, size: 55 }],
    legend: { live: false },
    series: [{ label: 't' }, ...series.map(([label, stroke, dash]) => ({ label, stroke, width: 1.5, dash }))],
  };
  const data = [[], ...series.map(() => [])];
  const plot = new uPlot(opts, data, el);
  new ResizeObserver(() => plot.setSize({ width: Math.max(el.clientWidth, 200), height: 150 })).observe(el);
  return { plot, data };
}

export class Plots {
  constructor() {
    this.speed = makePlot(document.getElementById('plot-speed'), 'speed, mm/min',
        [['actual', '#4fc3f7'], ['programmed', '#ffb74d', [6, 4]]]);
    this.override = makePlot(document.getElementById('plot-override'), 'override, %',
        [['feed', '#81c784'], ['rapid', '#ce93d8', [6, 4]]], () => [0, this.maxOverride]);
    this.load = makePlot(document.getElementById('plot-load'), 'spindle load, %',
        [['load', '#e57373'], ['target', '#ffb74d', [6, 4]]], () => [0, this.maxLoad]);
    this.loadTarget = 60;
    this.maxLoad = 120;
    this.pending = false;
    this.maxOverride = 200;
  }

  push(t, s) {
    const add = (p, values) => {
      p.data[0].push(t);
      values.forEach((v, i) => p.data[i + 1].push(v));
      while (p.data[0].length && p.data[0][0] < t - WINDOW_S) for (const col of p.data) col.shift();
    };
    add(this.speed, [s.feed_mm_min, s.programmed_feed_mm_min]);
    add(this.override, [s.feed_override_pct, s.rapid_override_pct]);
    add(this.load, [s.load_pct, this.loadTarget]);
    if (s.load_pct > this.maxLoad) this.maxLoad = Math.ceil(s.load_pct / 50) * 50;
    // Drawn once per animation frame at most: a slow frame does not queue up redraws.
    if (!this.pending) {
      this.pending = true;
      requestAnimationFrame(() => {
        this.pending = false;
        for (const p of [this.speed, this.override, this.load]) p.plot.setData(p.data);
      });
    }
  }

  setLoadTarget(pct) {
    this.loadTarget = pct;
  }

  setMaxOverride(pct) {
    this.maxOverride = Math.max(pct, 100);
  }
}
