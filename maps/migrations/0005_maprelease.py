import django.db.models.deletion
from django.conf import settings
from django.db import migrations, models


class Migration(migrations.Migration):
    dependencies = [
        ("maps", "0004_zones_and_versions"),
        migrations.swappable_dependency(settings.AUTH_USER_MODEL),
    ]

    operations = [
        migrations.CreateModel(
            name="MapRelease",
            fields=[
                (
                    "id",
                    models.BigAutoField(
                        auto_created=True, primary_key=True, serialize=False, verbose_name="ID"
                    ),
                ),
                ("number", models.PositiveIntegerField()),
                (
                    "version",
                    models.CharField(help_text="mapVersion sent to vehicles", max_length=50),
                ),
                (
                    "file_format",
                    models.CharField(
                        choices=[("LIF", "VDMA LIF 1.0 (JSON)")], default="LIF", max_length=10
                    ),
                ),
                ("content", models.BinaryField(editable=False)),
                (
                    "checksum",
                    models.CharField(help_text="SHA-256 of the file (mapHash)", max_length=64),
                ),
                ("size", models.PositiveIntegerField(default=0, help_text="bytes")),
                (
                    "revision",
                    models.PositiveIntegerField(help_text="the map's revision when released"),
                ),
                ("token", models.CharField(editable=False, max_length=64, unique=True)),
                ("note", models.CharField(blank=True, max_length=500)),
                ("created_at", models.DateTimeField(auto_now_add=True)),
                ("distributed_at", models.DateTimeField(blank=True, null=True)),
                (
                    "created_by",
                    models.ForeignKey(
                        blank=True,
                        null=True,
                        on_delete=django.db.models.deletion.SET_NULL,
                        related_name="+",
                        to=settings.AUTH_USER_MODEL,
                    ),
                ),
                (
                    "distributed_by",
                    models.ForeignKey(
                        blank=True,
                        null=True,
                        on_delete=django.db.models.deletion.SET_NULL,
                        related_name="+",
                        to=settings.AUTH_USER_MODEL,
                    ),
                ),
                (
                    "map",
                    models.ForeignKey(
                        on_delete=django.db.models.deletion.CASCADE,
                        related_name="releases",
                        to="maps.map",
                    ),
                ),
            ],
            options={
                "ordering": ["map", "-number"],
                "constraints": [
                    models.UniqueConstraint(
                        fields=("map", "number"), name="map_release_number_once"
                    ),
                    models.UniqueConstraint(
                        fields=("map", "version"), name="map_release_version_once"
                    ),
                ],
            },
        ),
    ]
