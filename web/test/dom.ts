// A small fake DOM for unit tests only: enough of `document` and its elements for a panel to be
// built and rendered in node (vitest runs without a browser), and a record of every element
// created, so that a test can tell what a render made anew and what it kept.

type Listener = (ev: { type: string; target: FakeElement }) => void;

export class FakeText {
  parentNode: FakeElement | null = null;
  constructor(public textContent: string) {}
  remove(): void {
    this.parentNode?.removeChild(this);
  }
}

type FakeNode = FakeElement | FakeText;

export class FakeElement {
  readonly tagName: string;
  id = "";
  hidden = false;
  parentNode: FakeElement | null = null;
  childNodes: FakeNode[] = [];
  readonly style: Record<string, string> = {};
  /// `data-*` attributes as the browser's `dataset` (kept apart from `attributes`).
  readonly dataset: Record<string, string> = {};
  readonly attributes = new Map<string, string>();
  private readonly classes = new Set<string>();
  private readonly listeners = new Map<string, Listener[]>();
  private chosen: string | null = null;

  constructor(tag: string) {
    this.tagName = tag.toUpperCase();
  }

  readonly classList = {
    add: (...names: string[]): void => names.forEach((n) => this.classes.add(n)),
    remove: (...names: string[]): void => names.forEach((n) => this.classes.delete(n)),
    contains: (name: string): boolean => this.classes.has(name),
    toggle: (name: string, on?: boolean): boolean => {
      const want = on ?? !this.classes.has(name);
      if (want) this.classes.add(name);
      else this.classes.delete(name);
      return want;
    },
  };

  get className(): string {
    return [...this.classes].join(" ");
  }
  set className(value: string) {
    this.classes.clear();
    for (const n of value.split(/\s+/)) if (n) this.classes.add(n);
  }

  get children(): FakeElement[] {
    return this.childNodes.filter((n): n is FakeElement => n instanceof FakeElement);
  }

  get parentElement(): FakeElement | null {
    return this.parentNode;
  }

  get isConnected(): boolean {
    let node: FakeElement | null = this;
    while (node.parentNode) node = node.parentNode;
    return node === fakeDocument.body;
  }

  get textContent(): string {
    return this.childNodes.map((n) => n.textContent).join("");
  }
  set textContent(text: string) {
    this.replaceChildren(text);
  }

  /// A `<select>`: its `<option>`s, and the value chosen (the first option's until one is set).
  get options(): FakeElement[] {
    return this.children.filter((c) => c.tagName === "OPTION");
  }
  get value(): string {
    if (this.tagName !== "SELECT") return this.chosen ?? this.attributes.get("value") ?? "";
    const values = this.options.map((o) => o.attributes.get("value") ?? o.textContent);
    return this.chosen !== null && values.includes(this.chosen) ? this.chosen : (values[0] ?? "");
  }
  set value(v: string) {
    this.chosen = v;
  }

  setAttribute(name: string, value: string): void {
    if (name === "class") this.className = value;
    else if (name === "hidden") this.hidden = true;
    else this.attributes.set(name, value);
  }
  getAttribute(name: string): string | null {
    return this.attributes.get(name) ?? null;
  }
  removeAttribute(name: string): void {
    this.attributes.delete(name);
  }

  addEventListener(type: string, fn: Listener): void {
    this.listeners.set(type, [...(this.listeners.get(type) ?? []), fn]);
  }
  removeEventListener(type: string, fn: Listener): void {
    this.listeners.set(type, (this.listeners.get(type) ?? []).filter((f) => f !== fn));
  }
  dispatch(type: string): void {
    for (const fn of this.listeners.get(type) ?? []) fn({ type, target: this });
  }

  private adopt(nodes: Array<FakeNode | string>): FakeNode[] {
    return nodes.map((n) => {
      const node = typeof n === "string" ? new FakeText(n) : n;
      node.parentNode?.removeChild(node);
      node.parentNode = this;
      return node;
    });
  }
  append(...nodes: Array<FakeNode | string>): void {
    this.childNodes.push(...this.adopt(nodes));
  }
  replaceChildren(...nodes: Array<FakeNode | string>): void {
    for (const n of this.childNodes) n.parentNode = null;
    this.childNodes = [];
    this.append(...nodes);
  }
  removeChild(node: FakeNode): void {
    this.childNodes = this.childNodes.filter((n) => n !== node);
    node.parentNode = null;
  }
  remove(): void {
    this.parentNode?.removeChild(this);
  }
  after(...nodes: Array<FakeNode | string>): void {
    const parent = this.parentNode;
    if (!parent) return;
    const adopted = parent.adopt(nodes);
    parent.childNodes.splice(parent.childNodes.indexOf(this) + 1, 0, ...adopted);
  }
  contains(node: FakeNode | null): boolean {
    for (let n: FakeNode | null = node; n; n = n.parentNode) if (n === this) return true;
    return false;
  }

  /// Selectors of one simple part: `tag`, `.class` (several: `.a.b`), `[attribute]`.
  matches(selector: string): boolean {
    return selector.split(",").some((one) => {
      const m = /^([a-z0-9]*)((?:\.[\w-]+)*)(?:\[([\w-]+)\])?$/.exec(one.trim());
      if (!m) return false;
      const [, tag, classes, attribute] = m;
      if (tag && this.tagName !== tag.toUpperCase()) return false;
      if (classes && !classes.split(".").filter(Boolean).every((c) => this.classes.has(c))) return false;
      if (attribute && !(attribute === "hidden" ? this.hidden : this.attributes.has(attribute))) return false;
      return true;
    });
  }
  closest(selector: string): FakeElement | null {
    for (let n: FakeElement | null = this; n; n = n.parentNode) if (n.matches(selector)) return n;
    return null;
  }
  querySelectorAll(selector: string): FakeElement[] {
    const out: FakeElement[] = [];
    const walk = (el: FakeElement): void => {
      for (const c of el.children) {
        if (c.matches(selector)) out.push(c);
        walk(c);
      }
    };
    walk(this);
    return out;
  }
  querySelector(selector: string): FakeElement | null {
    return this.querySelectorAll(selector)[0] ?? null;
  }

  getBoundingClientRect(): { left: number; top: number; right: number; bottom: number; width: number; height: number } {
    return { left: 0, top: 0, right: 0, bottom: 0, width: 0, height: 0 };
  }
  focus(): void {}
  click(): void {
    this.dispatch("click");
  }
}

/// Every element created since `installFakeDom`.
export const created: FakeElement[] = [];

const fakeDocument = {
  body: new FakeElement("body"),
  createElement(tag: string): FakeElement {
    const el = new FakeElement(tag);
    created.push(el);
    return el;
  },
  getElementById(id: string): FakeElement | null {
    const walk = (el: FakeElement): FakeElement | null => {
      if (el.id === id) return el;
      for (const c of el.children) {
        const found = walk(c);
        if (found) return found;
      }
      return null;
    };
    return walk(fakeDocument.body);
  },
  addEventListener(): void {},
  removeEventListener(): void {},
};

/// The globals a panel reaches for; `vi.unstubAllGlobals()` takes them away again.
export function fakeDomGlobals(): Record<string, unknown> {
  created.length = 0;
  fakeDocument.body.replaceChildren();
  return {
    document: fakeDocument,
    ResizeObserver: class {
      observe(): void {}
      disconnect(): void {}
    },
    requestAnimationFrame: (): number => 0,
    // no server in unit tests: what a panel fetches fails, as with the server gone
    fetch: (): Promise<never> => Promise.reject(new Error("no server in unit tests")),
  };
}
