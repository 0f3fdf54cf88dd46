// params_ui.js — one slider (with a number box for exact values) per parameter of the
// current surface. Ranges come from the preset or, for a typed expression, from the value.
import { niceStep, snap } from './format.js';

// Rebuilds the list in container. params: [{name, value, min, max}]; onChange(name, value,
// fromSlider) is called on every slider movement and on a committed number.
export function renderParams(container, params, onChange) {
  container.textContent = '';
  if (!params.length) {
    const p = document.createElement('p');
    p.className = 'hint';
    p.textContent = 'This surface has no parameters.';
    container.append(p);
    return;
  }
  for (const q of params) container.append(paramRow(q, onChange));
}

function paramRow(q, onChange) {
  const row = document.createElement('div');
  row.className = 'param';
  row.dataset.param = q.name;
  const id = `param-${q.name}`;
  let min = Math.min(q.min, q.value);
  let max = Math.max(q.max, q.value);
  const step = niceStep(min, max);

  const head = document.createElement('div');
  head.className = 'param-head';
  const label = document.createElement('label');
  label.htmlFor = id;
  label.textContent = q.name;
  const box = document.createElement('input');
  box.type = 'number';
  box.step = 'any';
  box.id = `${id}-value`;
  box.value = String(q.value);
  box.setAttribute('aria-label', `${q.name} value`);
  head.append(label, box);

  const slider = document.createElement('input');
  slider.type = 'range';
  slider.id = id;
  slider.dataset.param = q.name;
  slider.min = String(min);
  slider.max = String(max);
  slider.step = String(step);
  slider.value = String(q.value);

  const range = document.createElement('div');
  range.className = 'param-range';
  const lo = document.createElement('span');
  const hi = document.createElement('span');
  lo.textContent = String(min);
  hi.textContent = String(max);
  range.append(lo, hi);

  slider.addEventListener('input', () => {
    const v = snap(Number(slider.value), step);
    box.value = String(v);
    onChange(q.name, v, true);
  });
  box.addEventListener('change', () => {
    const v = Number(box.value);
    if (box.value.trim() === '' || !Number.isFinite(v)) {
      box.setAttribute('aria-invalid', 'true');
      return;
    }
    box.removeAttribute('aria-invalid');
    if (v < min) { min = v; slider.min = String(v); lo.textContent = String(v); }
    if (v > max) { max = v; slider.max = String(v); hi.textContent = String(v); }
    slider.value = String(v);
    onChange(q.name, v, false);
  });
  row.append(head, slider, range);
  return row;
}
