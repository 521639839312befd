"""What finished evaluations measured: ``results.csv``'s rows (``rows``) and ``episodes.parquet``
(``episodes``), the tables' and figures' selectors over those rows (``aggregate``), the paper's claims decided
from intervals (``claims``), and comparisons across studies and reruns (``compare``, ``rerun``).
"""
