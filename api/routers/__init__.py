"""One router per resource: :mod:`.jobs` (jobs and batches), :mod:`.sync` (the quick
synchronous calls) and :mod:`.meta` (health, kinds)."""
