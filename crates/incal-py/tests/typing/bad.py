"""Mistakes mypy --strict finds before anything runs."""

import incal

incal.tumble("tumble.csv", mount="pendulum", noize=1e-6)  # misspelt option
incal.tumble("tumble.csv", mount="sideways")  # not an allowed value
incal.gyro_rate("rate.csv")  # a required option left out
incal.plan.tumble(k1="ten")  # a number option given text
