"""Rule-based policies and bounds: condition-based rules, the clairvoyant oracle and random."""
