"""One router per resource: :mod:`.jobs` (jobs and batches), :mod:`.sync` (the quick
synchronous calls), :mod:`.meta` (health, kinds) and :mod:`.admin` (purge)."""
