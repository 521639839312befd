"""The report parts of task families: the sections and CSV files a family adds to a study's report.

They sit above the study (they read its rows through ``study.aggregate`` and write Markdown with
``study.markdown``), apart from the families' scene and protocol parts, which sit below the study and load
no study, torch or LeRobot module. A family names its report part by entry point
(``TaskFamily.report_entry_point``); ``study/family_report.py`` loads it when a report is written.
"""
