// Undo and redo: snapshots of what the user edits (the map's cells, start, goal, robot radius,
// discs), bounded in count and in bytes (a 1024 x 1024 map's cells are 1 MB a snapshot).

export class History {
  constructor(maxEntries = 100, maxBytes = 64 * 1024 * 1024) {
    this.maxEntries = maxEntries; this.maxBytes = maxBytes;
    this.done = []; this.undone = [];
    this.onChange = () => {};
  }

  static bytes(s) { return (s.occ ? s.occ.length : 0) + 256; }

  push(snap) {
    this.done.push(snap);
    this.undone = [];
    let total = this.done.reduce((a, s) => a + History.bytes(s), 0);
    while (this.done.length > this.maxEntries || (total > this.maxBytes && this.done.length > 1)) {
      total -= History.bytes(this.done.shift());
    }
    this.onChange();
  }

  // drop the last snapshot (an action that changed nothing)
  drop() { this.done.pop(); this.onChange(); }

  undo(current) {
    const s = this.done.pop();
    if (!s) return null;
    this.undone.push(current);
    this.onChange();
    return s;
  }

  redo(current) {
    const s = this.undone.pop();
    if (!s) return null;
    this.done.push(current);
    this.onChange();
    return s;
  }
}
