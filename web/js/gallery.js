// gallery.js — the gallery's pictures: one button per preset with the thumbnail the daemon
// renders itself (GET /v1/presets/{name}/thumbnail.png, computed once and cached there). A
// picture is asked for only when its button scrolls into the strip's view (each first request
// costs the daemon a coarse polygonisation), and only while the strip is open.

export class Gallery {
  // container: the scrolling strip; load(name) -> Promise<Blob>; pick(name) selects a preset.
  constructor(container, { load, pick }) {
    this.container = container;
    this.load = load;
    this.pick = pick;
    this.buttons = new Map();   // preset name -> button
    this.observer = new IntersectionObserver((entries) => this.visible(entries), { root: container });
  }

  fill(presets) {
    this.container.textContent = '';
    this.buttons.clear();
    for (const p of presets) {
      const b = document.createElement('button');
      b.type = 'button';
      b.className = 'thumb';
      b.dataset.preset = p.name;
      b.title = `${p.title}: ${p.about}`;
      const img = document.createElement('img');
      img.alt = p.title;
      img.width = 160;
      img.height = 120;
      const label = document.createElement('span');
      label.textContent = p.title;
      b.append(img, label);
      b.addEventListener('click', () => this.pick(p.name));
      this.container.append(b);
      this.buttons.set(p.name, b);
    }
  }

  // Starts (open) or stops (closed) loading the pictures that come into view.
  watch(open) {
    for (const b of this.buttons.values()) {
      if (open && !b.dataset.loaded) this.observer.observe(b);
      else this.observer.unobserve(b);
    }
  }

  visible(entries) {
    for (const e of entries) {
      if (!e.isIntersecting) continue;
      const b = e.target;
      this.observer.unobserve(b);
      b.dataset.loaded = 'loading';
      this.load(b.dataset.preset).then((blob) => {
        b.querySelector('img').src = URL.createObjectURL(blob);
        b.dataset.loaded = 'yes';
      }, () => { b.dataset.loaded = 'failed'; });
    }
  }

  // Shows only the presets keep(name) accepts; marks the current one.
  filter(keep, current) {
    for (const [name, b] of this.buttons) {
      b.hidden = !keep(name);
      b.classList.toggle('current', name === current);
    }
  }
}
