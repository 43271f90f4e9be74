"""Stage 1, the capture plan: its JSON Schema (`schema`) and the loader (`load`) that turns untrusted YAML into
frozen values (`Plan`), reporting every problem with file:line:col and a hint."""
