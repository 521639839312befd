"""One step and how steps run: a step and its key (``step``), the typed inputs the key hashes (``inputs``), what a
step leaves in its folder (``result``), the worker that runs steps through the table of step kinds (``worker``):
collect (``collect_step``), ``lerobot-train`` (``train_step``, ``train_schedule``, ``train_state``, launched by
``lerobot_process``) and LeRobot's evaluation (``eval_step``, ``blocks``), the policy checkpoint a step reads
(``checkpoint``), the evaluation env and its episode recording (``eval_env``, ``recording``), the device a step may
use (``device``), the executors that hand steps to workers (``executors``), finished steps linked from other
studies (``reuse``) and the pack that carries a study to another machine (``pack``).

Nothing here knows the study's grid: :mod:`..plan` builds steps from a config, this runs them.
"""
