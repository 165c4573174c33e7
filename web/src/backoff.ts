/// Reconnect delays: exponential backoff with jitter, capped, reset after a good connection.
///
/// Attempt 0 retries almost at once (a server restart is the common case, and it is back within
/// a second or two); then 0.5 s, 1 s, 2 s, ... up to `max`. Jitter (±`jitter`, a fraction)
/// spreads many tabs reconnecting to one restarted server.

export interface BackoffOptions {
  base: number;
  max: number;
  jitter: number;
}

export const DEFAULT_BACKOFF: BackoffOptions = { base: 250, max: 5000, jitter: 0.2 };

/// The delay in ms before reconnect attempt `attempt` (0-based); `random` returns [0, 1).
export function backoffDelay(attempt: number, options: BackoffOptions = DEFAULT_BACKOFF, random: () => number = Math.random): number {
  const exponent = Math.max(0, Math.min(attempt, 30));
  const raw = Math.min(options.max, options.base * 2 ** exponent);
  const spread = raw * options.jitter * (2 * random() - 1);
  return Math.max(0, Math.round(Math.min(options.max, raw + spread)));
}

/// Counts attempts; `next()` gives the next delay, `succeeded()` starts over.
export class Backoff {
  attempt = 0;
  constructor(
    private readonly options: BackoffOptions = DEFAULT_BACKOFF,
    private readonly random: () => number = Math.random,
  ) {}

  next(): number {
    return backoffDelay(this.attempt++, this.options, this.random);
  }

  succeeded(): void {
    this.attempt = 0;
  }
}
