// Knot recognition.
