"""The report parts of task families: the sections and CSV files a family adds to a study's report.

They sit above the study (they read its rows through ``study.results.aggregate`` and write Markdown with
``study.report.markdown``), apart from the families' scene and protocol parts, which sit below the study and load
no study, torch or LeRobot module. A family names its report part by entry point
(``TaskFamily.report_entry_point``); ``study/report/family_report.py`` loads it when a report is written.
"""
