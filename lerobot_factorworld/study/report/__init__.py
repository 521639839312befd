"""What people read: ``report.md`` (``markdown``, ``claims_markdown``), the figures (``plots``), ``report.html``
with its paired-episode viewer (``html_report``, ``html_page``, ``episode_videos``), the task families' own
sections (``family_report``), ``write`` (all of them from the finished steps) and the tables docs/ fences from
committed reports (``published``).
"""
