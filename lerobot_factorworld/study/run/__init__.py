"""One step and how steps run: the typed inputs a step's key hashes (``inputs``), running a collect,
``lerobot-train`` or LeRobot evaluation step cached by its key (``steps``), the policy checkpoint a step reads
(``checkpoint``), the evaluation env and its episode recording (``eval_env``, ``recording``), the executors that
run the steps they are handed (``executors``), and finished steps linked from other studies (``reuse``).

Nothing here knows the study's grid: :mod:`..plan` builds steps from a config, this runs them.
"""
