// Render requests of an interactive view: at most one in flight and one
// pending. A newer preview (while dragging) replaces the pending one; a final
// (full-size) request aborts whatever is in flight, since its answer would be
// stale, and goes at once. Answers of aborted or superseded requests are
// dropped, never shown.

export class RenderScheduler {
  // send(job, signal) -> Promise of a prepared frame; show(frame, job) draws it;
  // fail(error, job) reports an error; busy(bool) shows activity.
  constructor({ send, show, fail, busy }) {
    Object.assign(this, { send, show, fail, busy });
    this.inflight = null;   // { job, controller, seq }
    this.pending = null;    // job
    this.seq = 0;
    this.shownSeq = 0;
    this.sent = 0;          // requests sent (the browser test reads these)
    this.aborted = 0;
  }

  submit(job) {
    if (!this.inflight) return this.start(job);
    if (job.final) {
      this.pending = null;
      this.inflight.controller.abort();
      this.aborted++;
      this.inflight = null;
      return this.start(job);
    }
    this.pending = job;
  }

  cancelAll() {
    this.pending = null;
    if (this.inflight) {
      this.inflight.controller.abort();
      this.aborted++;
      this.inflight = null;
    }
    this.busy(false);
  }

  start(job) {
    const entry = { job, controller: new AbortController(), seq: ++this.seq };
    this.inflight = entry;
    this.sent++;
    this.busy(true, job);
    this.send(job, entry.controller.signal).then(
      (frame) => this.finish(entry, frame, null),
      (error) => this.finish(entry, null, error),
    );
  }

  finish(entry, frame, error) {
    if (this.inflight !== entry) return;  // aborted and replaced: its answer is stale
    this.inflight = null;
    if (error) {
      if (error.name !== 'AbortError') this.fail(error, entry.job);
    } else if (entry.seq > this.shownSeq) {
      this.shownSeq = entry.seq;
      this.show(frame, entry.job);
    }
    const next = this.pending;
    this.pending = null;
    if (next) this.start(next);
    else this.busy(false);
  }
}
