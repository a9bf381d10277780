"""A call to a peer's service that never blocks its caller: it runs on its own thread and
the caller polls it; a call that does not answer within `timeout` is reported and
abandoned. At most one call runs at a time, so a peer that hangs costs one thread, not
one per request. No ROS here: the callable does the ROS part."""
import threading
import time


class ServiceCall:
    """`fn(*args)` on a helper thread. submit() starts a call (False while one is still
    running, hung ones included); poll() reports the outcome exactly once:
    ('ok', result), ('failed', exception) or ('timeout', seconds)."""

    def __init__(self, fn, timeout, name='service', clock=time.monotonic):
        if not timeout > 0:
            raise ValueError('timeout must be > 0, got %r' % (timeout,))
        self.fn = fn
        self.timeout = float(timeout)
        self.name = name
        self.clock = clock
        self._lock = threading.Lock()
        self._thread = None
        self._started = None          # clock time of the call being waited for
        self._outcome = None
        self._call_id = 0
        self.counts = {'ok': 0, 'failed': 0, 'timeout': 0, 'refused': 0}

    @property
    def busy(self):
        """A call still runs (possibly one abandoned after its timeout)."""
        return self._thread is not None and self._thread.is_alive()

    def submit(self, *args):
        with self._lock:
            if self.busy:
                self.counts['refused'] += 1
                return False
            self._call_id += 1
            call_id = self._call_id
            self._started = self.clock()
            self._outcome = None
        self._thread = threading.Thread(target=self._run, args=(call_id, args),
                                        name='%s_call' % self.name, daemon=True)
        self._thread.start()
        return True

    def _run(self, call_id, args):
        try:
            outcome = ('ok', self.fn(*args))
        except Exception as e:        # any failure of the peer or the proxy: reported
            outcome = ('failed', e)
        with self._lock:
            if call_id == self._call_id and self._started is not None:
                self._outcome = outcome

    def poll(self):
        """None while nothing new; else the outcome of the call waited for."""
        with self._lock:
            if self._started is None:
                return None
            if self._outcome is not None:
                outcome, self._outcome, self._started = self._outcome, None, None
                self.counts[outcome[0]] += 1
                return outcome
            waited = self.clock() - self._started
            if waited > self.timeout:
                self._started = None           # abandoned: its late answer is ignored
                self.counts['timeout'] += 1
                return ('timeout', waited)
        return None
