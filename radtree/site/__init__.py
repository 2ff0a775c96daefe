"""Sites: the street canyon (and, later, blocks of offices) around the studied façade."""
