"""Adapters that run vision-language-action models served elsewhere as dexbench policies.

A VLA runs in its own environment (its own Python, CUDA and weights), often on another
machine; the adapter speaks the model server's wire protocol, turns the batched env's
observations into one request per environment and plays back the returned action
chunks. `openpi` serves pi0 / pi0.5 over a websocket, `openvla_oft` OpenVLA-OFT over
HTTP. `lerobot_policy` is the exception: it runs any LeRobot `PreTrainedPolicy` in this
process, with the policy's own pre- and post-processors.
"""
