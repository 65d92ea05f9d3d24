//! The certificate as a machine-readable Digital Calibration Certificate:
//! XML of PTB's DCC schema, version 3.2.0 (`https://ptb.de/dcc`), with
//! every coefficient a D-SI 2.1.0 quantity (`https://ptb.de/si`): value,
//! unit, and expanded uncertainty with its coverage factor and
//! probability (`si:expandedUnc`, GUM 6.2: `U95 = k95 u`).
//!
//! Sources: S. Hackel, F. Härtig, J. Hornig, T. Wiedenhöfer, "The Digital
//! Calibration Certificate", PTB-Mitteilungen 127(4), 2017; D. Hutzschenreuter
//! et al., "SmartCom Digital System of Units (D-SI) Guide", Zenodo
//! 10.5281/zenodo.3522631, 2019. The XSDs (LGPL-3.0) are kept with their
//! licence under `tests/dcc/` and every document this module writes is
//! validated against them in the tests.
//!
//! Units: the SI units of incal's documents are written in D-SI notation
//! (`\radian`, `\metre`, `\degree\second\tothe{-1}`, `\one`); the units
//! relative to the instrument (local gravity `g`, the instrument's output)
//! are not SI and are written with D-SI's `|` mark for a non-SI unit
//! (`|g`, `|output\|g\tothe{-1}`), named in a statement of the certificate.

use incal::document::ResultDocument;
use incal::units::Unit;

/// What the certificate says beside the result.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DccInfo {
    /// The certificate number (unique identifier).
    pub number: String,
    /// The laboratory's name.
    pub lab_name: String,
    /// Its address (one line).
    pub lab_address: String,
    /// ISO 3166-1 alpha-2 country code of the laboratory (`ZZ`: not stated).
    pub country: String,
    /// The customer, if stated.
    pub customer: Option<String>,
    /// Date of calibration, `YYYY-MM-DD`.
    pub calibration_date: String,
    /// Date of issue, `YYYY-MM-DD`.
    pub issue_date: String,
    /// Who authorised it and in which function.
    pub signatory: Option<(String, String)>,
    /// Record and chain of the store it was issued from, for the comment.
    pub record: Option<String>,
}

/// XML text: the report's escaping of `& < > " '` ([`crate::format::esc`],
/// whose entities XML reads too), after every control character XML 1.0
/// does not allow becomes a space.
fn x(s: &str) -> String {
    let allowed = |c: char| (c as u32) >= 0x20 || matches!(c, '\t' | '\n' | '\r');
    crate::format::esc(&s.replace(|c: char| !allowed(c), " "))
}

/// A DCC text: `<dcc:TAG><dcc:content>TEXT</dcc:content></dcc:TAG>`, the
/// text trimmed and never empty (the schema's `notEmptyString`).
fn text(tag: &str, s: &str) -> String {
    let t = s.split_whitespace().collect::<Vec<_>>().join(" ");
    let t = if t.is_empty() {
        "not stated".to_string()
    } else {
        t
    };
    format!(
        "<dcc:{tag}><dcc:content>{}</dcc:content></dcc:{tag}>",
        x(&t)
    )
}

/// The D-SI unit of an incal unit (module docs).
pub fn dsi_unit(u: &Unit) -> String {
    match u {
        Unit::Rad => "\\radian".into(),
        Unit::Deg => "\\degree".into(),
        Unit::M => "\\metre".into(),
        Unit::DegPerS => "\\degree\\second\\tothe{-1}".into(),
        Unit::RadPerS => "\\radian\\second\\tothe{-1}".into(),
        Unit::One => "\\one".into(),
        Unit::G => "|g".into(),
        Unit::GPerG2 => "|g\\tothe{-1}".into(),
        Unit::GPerG3 => "|g\\tothe{-2}".into(),
        Unit::Output => "|output".into(),
        Unit::OutputPerG => "|output|g\\tothe{-1}".into(),
        Unit::OutputPerDegS => "|output\\degree\\tothe{-1}\\second".into(),
        Unit::Other(s) => format!("|{s}"),
    }
}

/// A D-SI decimal (`[-+]?digits[.digits][E±n]`): the shortest text that
/// reads back as the same double.
fn decimal(v: f64) -> String {
    ryu::Buffer::new().format_finite(v).to_string()
}

/// The DCC XML of result `doc` under `info` (module docs): administrative
/// data (software, core data, the instrument, the laboratory, the
/// signatory, the customer), then one measurement result holding every
/// coefficient as a D-SI real with its expanded uncertainty.
pub fn dcc_xml(doc: &ResultDocument, info: &DccInfo) -> String {
    let mut s = String::with_capacity(8192);
    s.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    s.push_str("<dcc:digitalCalibrationCertificate xmlns:dcc=\"https://ptb.de/dcc\" xmlns:si=\"https://ptb.de/si\" schemaVersion=\"3.2.0\">\n");
    s.push_str("<dcc:administrativeData>\n");
    s.push_str(&format!(
        "<dcc:dccSoftware><dcc:software>{}<dcc:release>{}</dcc:release></dcc:software></dcc:dccSoftware>\n",
        text("name", "incal"),
        x(&doc.incal_version)
    ));
    let country = if info.country.len() == 2 && info.country.bytes().all(|b| b.is_ascii_uppercase())
    {
        info.country.as_str()
    } else {
        "ZZ"
    };
    s.push_str(&format!(
        "<dcc:coreData><dcc:countryCodeISO3166_1>{country}</dcc:countryCodeISO3166_1><dcc:usedLangCodeISO639_1>en</dcc:usedLangCodeISO639_1><dcc:mandatoryLangCodeISO639_1>en</dcc:mandatoryLangCodeISO639_1><dcc:uniqueIdentifier>{}</dcc:uniqueIdentifier><dcc:beginPerformanceDate>{d}</dcc:beginPerformanceDate><dcc:endPerformanceDate>{d}</dcc:endPerformanceDate><dcc:performanceLocation>laboratory</dcc:performanceLocation><dcc:issueDate>{}</dcc:issueDate></dcc:coreData>\n",
        x(info.number.trim()),
        x(&info.issue_date),
        d = x(&info.calibration_date),
    ));
    let serial = doc.instrument.serial.as_deref().unwrap_or("not stated");
    let model = doc.instrument.model.as_deref();
    s.push_str(&format!(
        "<dcc:items><dcc:item>{}<dcc:manufacturer>{}</dcc:manufacturer>{}<dcc:identifications><dcc:identification><dcc:issuer>manufacturer</dcc:issuer><dcc:value>{}</dcc:value>{}</dcc:identification></dcc:identifications></dcc:item></dcc:items>\n",
        text("name", &format!("{} {serial}", model.unwrap_or("instrument"))),
        text("name", "not stated"),
        model.map(|m| format!("<dcc:model>{}</dcc:model>", x(m.trim()))).unwrap_or_default(),
        x(serial.trim()),
        text("name", "serial number"),
    ));
    s.push_str(&format!(
        "<dcc:calibrationLaboratory><dcc:contact>{}<dcc:location>{}</dcc:location></dcc:contact></dcc:calibrationLaboratory>\n",
        text("name", &info.lab_name),
        text("further", &info.lab_address),
    ));
    let (who, role) = info
        .signatory
        .clone()
        .unwrap_or_else(|| ("not stated".into(), "not authorised".into()));
    s.push_str(&format!(
        "<dcc:respPersons><dcc:respPerson><dcc:person>{}</dcc:person><dcc:role>{}</dcc:role><dcc:mainSigner>true</dcc:mainSigner></dcc:respPerson></dcc:respPersons>\n",
        text("name", &who),
        x(role.trim()),
    ));
    let customer = info.customer.as_deref().unwrap_or("not stated");
    s.push_str(&format!(
        "<dcc:customer>{}<dcc:location>{}</dcc:location></dcc:customer>\n",
        text("name", customer),
        text("further", "not stated"),
    ));
    s.push_str("<dcc:statements><dcc:statement>");
    s.push_str(&text("declaration", "Units marked | are not SI: g is the local gravity of the test, output the instrument's own output unit. Uncertainties are expanded uncertainties U95 = k95 u, k95 from the Student t distribution of each coefficient's effective degrees of freedom (GUM 6.2, G.4)."));
    s.push_str("</dcc:statement></dcc:statements>\n");
    s.push_str("</dcc:administrativeData>\n<dcc:measurementResults><dcc:measurementResult>\n");
    s.push_str(&text("name", &doc.title));
    s.push_str(&format!(
        "\n<dcc:usedMethods><dcc:usedMethod>{}</dcc:usedMethod></dcc:usedMethods>\n<dcc:results>\n",
        text(
            "name",
            &format!(
                "incal {}: {}",
                doc.procedure,
                crate::certificate::method_of(doc.procedure)
            )
        )
    ));
    for (name, c) in doc.coefficients.iter() {
        let k = if c.k95 >= 1.0 { c.k95 } else { 1.0 };
        s.push_str(&format!(
            "<dcc:result>{}<dcc:data><dcc:quantity><si:real><si:value>{}</si:value><si:unit>{}</si:unit><si:expandedUnc><si:uncertainty>{}</si:uncertainty><si:coverageFactor>{k:.3}</si:coverageFactor><si:coverageProbability>0.95</si:coverageProbability><si:distribution>{}</si:distribution></si:expandedUnc></si:real></dcc:quantity></dcc:data></dcc:result>\n",
            text("name", name),
            decimal(c.value),
            x(&dsi_unit(&c.unit)),
            decimal(c.u95.abs()),
            if c.dof.is_some_and(f64::is_finite) { "student-t" } else { "normal" },
        ));
    }
    s.push_str("</dcc:results>\n</dcc:measurementResult></dcc:measurementResults>\n");
    if let Some(r) = &info.record {
        s.push_str(&format!("<dcc:comment>{}</dcc:comment>\n", x(r)));
    }
    s.push_str("</dcc:digitalCalibrationCertificate>\n");
    s
}
