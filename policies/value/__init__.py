"""What information is worth: rule families tuned with the same budget, the value study."""
